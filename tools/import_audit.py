"""Record what every Python process of a run imports and compiles from source (the evidence
behind tools/bytecode.py's rule).

    .venv/bin/python tools/import_audit.py install DIR   # hook every process of .venv
    PYTHONDONTWRITEBYTECODE=1 .venv/bin/python -m pytest ...   # or snakemake, any run
    .venv/bin/python tools/import_audit.py report DIR    # what was imported / compiled
    .venv/bin/python tools/import_audit.py uninstall

``install`` writes a ``.pth`` file into the environment's site-packages, so every process
of that interpreter (pytest workers, Snakemake's script jobs, subprocesses) starts the hook.
The hook logs each ``compile`` audit event on a ``.py`` file at once (a forked child that
leaves with ``os._exit`` is still seen) and, at exit, the files of the modules loaded.
Use it in a throw-away clone: the hook costs little, but it is not part of the project.
"""

import atexit
import os
import re
import sys
import sysconfig
from collections import Counter
from pathlib import Path

PTH = "zz_accelcal_import_audit.pth"


def _site():
    return Path(sysconfig.get_path("purelib"))


def start(out_dir):
    """Hook this process: log source compiles now and loaded module files at exit."""
    out = Path(out_dir)

    def audit(event, args):
        if event == "compile" and isinstance(args[1], str) and args[1].endswith(".py"):
            with open(out / f"{os.getpid()}.compiled", "a") as f:
                f.write(args[1] + "\n")

    def loaded():
        files = {getattr(m, "__file__", None) for m in list(sys.modules.values())}
        with open(out / f"{os.getpid()}.imported", "a") as f:
            f.writelines(p + "\n" for p in sorted(filter(None, files)))

    sys.addaudithook(audit)
    atexit.register(loaded)


def install(out_dir):
    out = Path(out_dir).resolve()
    out.mkdir(parents=True, exist_ok=True)
    here = Path(__file__).resolve()
    line = (f"import importlib.util as u; s = u.spec_from_file_location('_import_audit', {str(here)!r}); "
            f"m = u.module_from_spec(s); s.loader.exec_module(m); m.start({str(out)!r})\n")
    (_site() / PTH).write_text(line)


def _lines(out, suffix):
    for p in Path(out).glob(f"*.{suffix}"):
        yield from p.read_text().splitlines()


def report(out_dir):
    # Here, not at the top: the hook above is loaded into every process, which must not
    # import the rule (tools/ is on sys.path only when this file runs as a script).
    from bytecode import SKIP

    site = str(_site())
    procs = len(list(Path(out_dir).glob("*.imported")))
    imported = {p for p in _lines(out_dir, "imported") if p.startswith(site)}
    compiled = Counter(p for p in _lines(out_dir, "compiled") if p.startswith(site))
    skipped = sorted(p for p in imported if SKIP.search(p))
    tops = Counter(re.split(r"[/\\]", p[len(site) + 1:])[0] for p in imported)
    print(f"processes that reached exit: {procs}; site-packages files imported: {len(imported)}")
    print(f"imported files the rule skips: {len(skipped)}")
    for p in skipped:
        print("  ", p)
    print(f"site-packages files compiled from source: {len(compiled)} files, "
          f"{sum(compiled.values())} compiles")
    for p, n in compiled.most_common():
        print(f"  {n:5d} {p}")
    print("top-level entries imported:", " ".join(sorted(tops)))


def main(argv):
    cmd = argv[1] if len(argv) > 1 else ""
    if cmd == "install" and len(argv) == 3:
        install(argv[2])
    elif cmd == "report" and len(argv) == 3:
        report(argv[2])
    elif cmd == "uninstall":
        (_site() / PTH).unlink(missing_ok=True)
    else:
        print(__doc__, file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
