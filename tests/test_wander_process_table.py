"""One table for the wander processes: no comparison on a process's, term's or family's
name outside :mod:`accelcal.discrepancy.wander_process` (the if/elif on the name that was
in six modules before; what a process does is a method of its entry).  Files are parsed.

A name the wander table shares with another concept (``random_walk`` and ``gauss_markov``
are noise-library terms too, ``none`` and ``sum`` are common words) counts only where the
other side of the comparison is a process or a family (``proc``, ``process``, ``family``,
``.get("process")``, ``["term"]``); the others count anywhere.
"""

from __future__ import annotations

import ast
from pathlib import Path

from accelcal.discrepancy.wander_process import FAMILIES, PROCESSES
from accelcal.noise.terms import TERMS

ROOT = Path(__file__).resolve().parents[1]
TABLE = ROOT / "src" / "accelcal" / "discrepancy" / "wander_process.py"
NAMES = set(PROCESSES) | {p.term for p in PROCESSES.values()} | set(FAMILIES)
SHARED = {n for n in NAMES if n in TERMS or n in ("none", "sum")}
ABOUT = ("proc", "process", "family", "wander_family")   # a name or attribute so called
KEYS = ("process", "term")                                # a mapping's key so called


def _strings(node) -> set[str]:
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return {node.value}
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return {e.value for e in node.elts if isinstance(e, ast.Constant) and isinstance(e.value, str)}
    return set()


def _about_a_process(node) -> bool:
    """Whether ``node`` is a process, term or family: a name or attribute so called, or a
    ``.get("process")`` / ``["process"]`` of a mapping."""
    if isinstance(node, ast.Name):
        return node.id in ABOUT
    if isinstance(node, ast.Attribute):
        return node.attr in ABOUT
    if isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "get" and node.args:
        return _strings(node.args[0]) & set(KEYS) != set()
    if isinstance(node, ast.Subscript):
        return _strings(node.slice) & set(KEYS) != set()
    return False


def name_comparisons(path: Path) -> list[str]:
    """``file:line: source`` of every comparison on a wander process's name in ``path``."""
    out, text = [], path.read_text()
    if not any(f'"{n}"' in text or f"'{n}'" in text for n in NAMES):  # no name: nothing to parse
        return out
    for node in ast.walk(ast.parse(text, filename=str(path))):
        if not isinstance(node, ast.Compare):
            continue
        sides = [node.left, *node.comparators]
        named = set().union(*map(_strings, sides)) & NAMES
        if named - SHARED or (named and any(map(_about_a_process, sides))):
            out.append(f"{path.relative_to(ROOT)}:{node.lineno}: {ast.unparse(node)}")
    return out


def sources() -> list[Path]:
    return sorted(p for d in ("src", "workflow") for p in (ROOT / d).rglob("*.py") if p != TABLE)


def test_no_module_compares_a_wander_process_name():
    assert [c for p in sources() for c in name_comparisons(p)] == []


def test_the_check_sees_the_old_branches(tmp_path):
    old = tmp_path / "old.py"
    old.write_text(
        'def f(nm, w, family, term):\n'
        '    a = nm.get("process") == "gauss_markov"\n'
        '    b = nm.get("process") in ("per_placement", "flicker")\n'
        '    c = nm["term"] == "per_placement_offset"\n'
        '    d = family == "sum"\n'
        '    e = "bias_wander" != term\n'
        '    f = nm.get("term") not in (None, "none")\n'
        '    ok = term == "white" or nm.get("x") == "random_walk" or correction == "none"\n')
    found = [c.split(": ", 1)[1] for c in name_comparisons_in(old, tmp_path)]
    assert len(found) == 6 and not any("white" in c for c in found), found


def name_comparisons_in(path: Path, root: Path) -> list[str]:
    global ROOT
    saved, ROOT = ROOT, root
    try:
        return name_comparisons(path)
    finally:
        ROOT = saved
