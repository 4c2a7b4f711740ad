"""The README leads and the documentation holds: the two commands and a first calibration
open the README, and that first calibration runs as printed; every `accelcal` command
shown in the README and docs/ parses with the command line's own parser; every Python
block outside the extending guide (whose blocks tests/test_examples.py checks) runs; the
layout names every package; the site builds with `mkdocs build --strict`."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from accelcal import cli

REPO = Path(__file__).resolve().parents[1]
PAGES = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
sys.path.insert(0, str(REPO / "tools"))
from docs_index import index_text  # noqa: E402


def _blocks(text: str, lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", text, flags=re.S)


def _commands(text: str) -> list[str]:
    """The ``accelcal ...`` command lines of a page's shell blocks (continuations joined, comments cut)."""
    out = []
    for block in _blocks(text, "sh"):
        for line in block.replace("\\\n", " ").splitlines():
            line = line.split(" # ")[0].split("  #")[0].strip()
            if line.startswith("accelcal "):
                out.append(line)
    return out


def test_the_readme_leads_with_the_two_commands_and_a_first_calibration():
    lines = (REPO / "README.md").read_text().splitlines()
    assert len(lines) < 250, len(lines)
    head = "\n".join(lines[:40])
    ci = (REPO / ".ci" / "run").read_text().strip().splitlines()[-1]
    test_command = "sh tools/setup.sh && .venv/bin/python -m pytest"
    assert test_command in head and ci == test_command  # .ci/run runs exactly the README's test command
    assert "sh tools/setup.sh && .venv/bin/snakemake all" in head
    assert "accelcal calibrate " in head


def test_every_page_is_in_the_site_and_linked_from_the_readme():
    nav = (REPO / "mkdocs.yml").read_text()
    readme = (REPO / "README.md").read_text()
    for page in sorted((REPO / "docs").glob("*.md")):
        assert f": {page.name}" in nav, page.name
        assert page.name == "index.md" or f"(docs/{page.name})" in readme, page.name
    assert (REPO / "docs" / "index.md").read_text() == index_text(readme), "run python tools/docs_index.py"


def undocumented_packages(layout: str, src: Path) -> list[str]:
    """The subpackages under ``src``'s packages that ``layout`` does not name as ``name/``."""
    return [f"{pkg.name}/{sub.name}" for pkg in sorted(src.iterdir()) if (pkg / "__init__.py").exists()
            for sub in sorted(pkg.iterdir()) if sub.is_dir() and (sub / "__init__.py").exists()
            and f"`{sub.name}/`" not in layout]


def test_the_layout_names_every_package():
    """docs/development.md's layout names every subpackage (it once left out the gyroscope's)."""
    text = (REPO / "docs" / "development.md").read_text()
    layout = text[text.index("## Layout"):text.index("\n## ", text.index("## Layout") + 1)]
    assert undocumented_packages(layout, REPO / "src") == []
    assert undocumented_packages("`gyro/` `cli/`", REPO / "src")  # the check sees a package left out


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_command_shown_parses(page):
    parser = cli._parser()  # the command line's own parser
    for command in _commands(page.read_text()):
        try:
            parser.parse_args(shlex.split(command)[1:])
        except SystemExit as e:
            pytest.fail(f"{page.name}: `{command}` does not parse (exit {e.code})")


def test_the_command_check_sees_an_option_that_does_not_exist():
    with pytest.raises(SystemExit):
        cli._parser().parse_args(["calibrate", "x.csv", "--no-such-option"])


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    """What the pages' Python blocks open: a calibration.json and the flight.csv it applies to."""
    from accelcal.simulation import random_directions, simulate_recording

    folder = tmp_path_factory.mktemp("docs")
    rng = np.random.default_rng(3)
    rec = simulate_recording(rng, np.vstack([[0, 0, 1.0], random_directions(rng, 23)]), 9.80665, np.eye(3),
                             np.array([0.02, -0.01, 0.03]), noise_std=0.01)
    for name in ("session.csv", "flight.csv"):
        np.savetxt(folder / name, np.column_stack([rec["t"], rec["acc"]]), delimiter=",", header="t,ax,ay,az",
                   comments="")
    assert cli.main(["calibrate", str(folder / "session.csv"), "--out", str(folder / "calibration.json")]) == 0
    return folder


def test_the_readmes_first_calibration_runs_as_printed(session, tmp_path, monkeypatch, capsys):
    """The README's first commands (calibrate, apply, noise, export) run as written, on a
    session, a flight and a static record made for them: exit 0 and every file written."""
    readme = (REPO / "README.md").read_text()
    section = readme[readme.index("## A first calibration"):]
    commands = _commands(section[:section.index("\n## ")])
    assert [c.split()[1] for c in commands] == ["calibrate", "apply", "noise", "export"]
    for name in ("session.csv", "flight.csv"):
        (tmp_path / name).write_bytes((session / name).read_bytes())
    rng = np.random.default_rng(1)
    n = 30_000  # five minutes at 100 Hz at rest
    np.savetxt(tmp_path / "static.csv", np.column_stack([np.arange(n) / 100.0, [0, 0, 9.80665] + 0.01 *
               rng.standard_normal((n, 3))]), delimiter=",", header="t,ax,ay,az", comments="", fmt="%.6f")
    monkeypatch.chdir(tmp_path)
    for command in commands:
        args = shlex.split(command)[1:]
        assert cli.main(args) == 0, (command, capsys.readouterr().err[-2000:])
        assert (tmp_path / args[args.index("--out") + 1]).stat().st_size > 0, command


@pytest.mark.parametrize("page", [p for p in PAGES if p.name not in ("extending.md",)], ids=lambda p: p.name)
def test_every_python_block_runs(page, session):
    for code in _blocks(page.read_text(), "python"):
        p = subprocess.run([sys.executable, "-c", code], cwd=session, capture_output=True, text=True, timeout=300)
        assert p.returncode == 0, f"{page.name}:\n{code}\n{p.stderr[-2000:]}"


def test_the_site_builds_strictly(tmp_path):
    mkdocs = Path(sys.executable).with_name("mkdocs")
    p = subprocess.run([str(mkdocs), "build", "--strict", "-q", "-f", str(REPO / "mkdocs.yml"), "-d",
                        str(tmp_path / "site")], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-3000:]
    assert (tmp_path / "site" / "gyroscope" / "index.html").exists()
