"""Digest of the requirements the lock is compiled from (pyproject.toml + build backend)."""
import hashlib
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def requirement_lines() -> list[str]:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    lines = list(project["dependencies"])
    # every extra is locked (the README's commands install them all); an extra that names
    # another extra of accelcal itself ("accelcal[plots]") adds no package of its own
    for _extra, reqs in sorted(project.get("optional-dependencies", {}).items()):
        lines += [r for r in reqs if not r.startswith(project["name"] + "[")]
    build = (ROOT / "tools" / "build-requirements.in").read_text().splitlines()
    lines += [ln.strip() for ln in build if ln.strip() and not ln.startswith("#")]
    lines.append("requires-python" + project["requires-python"])
    return sorted(" ".join(ln.split()) for ln in lines)


def requirements_digest() -> str:
    return hashlib.sha256("\n".join(requirement_lines()).encode()).hexdigest()
