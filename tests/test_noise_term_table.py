"""One table for the noise terms: outside :mod:`accelcal.noise.terms` no code branches on
a term's id, keeps a table keyed by term ids, or picks a named term out of a per-term
mapping (what a term does, how it is labelled and whether the report, the planner and
the exports use it are attributes of its entry).  Files are parsed, not imported.

Three shapes are counted in ``src/accelcal`` (terms.py itself apart):

* ``compare``: a comparison with a term id (``term == "white"``, ``k in ("random_walk", "drift_ramp")``,
  ``case "white":``);
* ``table``: a literal holding two or more term ids (a dict keyed by them, a tuple or list
  of them: ``IEEE_TERMS``, ``PLANNED``, ``for k in ("bias_instability", "random_walk")``);
* ``pick``: a subscript by a term id (``terms["white"]``, ``terms.get("white")``).

Naming one term to *use* it (a noise model ``{"random_walk": 1.0}``, ``noise_term("white")``,
``fit_avar(..., ("white",), fs)``) is not counted: that is the public API's way of
writing a model.  What remains is listed in :data:`ALLOWED` with its reason: mostly a
consumer's file format whose field is spelled like a term id (Kalibr's and the noise
JSON's ``random_walk``), and the stochastic layer's base model (outside the noise package).
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

from accelcal.noise.terms import TERMS

ROOT = Path(__file__).resolve().parents[1]
TABLE = ROOT / "src" / "accelcal" / "noise" / "terms.py"
IDS = frozenset(TERMS)

_NOISE_JSON = ("the noise report's exported values ('noise_density', 'random_walk': the keys of "
               "accelcal.noise.export.exported_values, named after Kalibr's imu.yaml fields), not a term id")
_REFERENCES = ("the `references` argument's field names ({sensor: {'white': N, 'floor': ADEV}}: a datasheet's "
               "values), not a term id")
_AVR = "allan_variance_ros's reading, keyed by the imu.yaml field it writes (its analysis.py), not a term id"
_CANDIDATES = ("the stochastic layer's default `candidates` setting (a configuration value the user overrides in "
               "config: which terms to try is the user's choice), outside the noise package")
_BASE = ("the discrepancy stochastic layer's base model is white noise by its definition (candidates are "
         "added to it): the layer's rule, outside the noise package")

#: (file relative to the repository, ast.unparse of the node) -> why it is not a term's behaviour.
ALLOWED = {
    ("src/accelcal/noise/report.py", "e['random_walk']"): _NOISE_JSON,
    ("src/accelcal/noise/report.py", "ex[0]['random_walk']"): _NOISE_JSON,
    ("src/accelcal/noise/figures.py", "ex['random_walk']"): _NOISE_JSON,
    ("src/accelcal/export/kfgins.py", "vals['gyroscope', 'random_walk']"): _NOISE_JSON,
    ("src/accelcal/export/kfgins.py", "vals['accelerometer', 'random_walk']"): _NOISE_JSON,
    ("src/accelcal/noise/figures.py", "'white' in ref"): _REFERENCES,
    ("src/accelcal/noise/figures.py", "ref['white']"): _REFERENCES,
    ("src/accelcal/noise/export.py", "{'noise_density': white, 'random_walk': walk, 'bias_instability': "
     "float(adev[i]), 'bias_instability_tau_s': float(taus[i])}"): _AVR,
    ("src/accelcal/discrepancy/stochastic/layer.py", "('quantization', 'bias_instability', 'random_walk', "
     "'drift_ramp', 'sinusoid')"): _CANDIDATES,
    ("src/accelcal/discrepancy/stochastic/layer.py", "'white' in cand"): _BASE,
    ("src/accelcal/discrepancy/stochastic/layer.py", "current.term_ids == ('white',)"): _BASE,
    ("src/accelcal/discrepancy/stochastic/layer.py", "current.coefficients['white']"): _BASE,
    ("src/accelcal/discrepancy/allan_check.py", "a.fit_before['white']"): _BASE,
    ("src/accelcal/discrepancy/wander_process.py", "('per_placement', 'gauss_markov', 'random_walk')"):
        "a wander family's REML grid members (discrepancy/wander/members.py's table, whose ids two noise "
        "terms share): which members a family's grid holds, not a noise term's behaviour",
}


def _ids_in(node) -> list[str]:
    """The term ids ``node`` spells: a string constant, or the constants of a tuple, list or set."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return [node.value] if node.value in IDS else []
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return [e.value for e in node.elts if isinstance(e, ast.Constant) and e.value in IDS]
    return []


def _kind(node, not_a_table: bool) -> str | None:
    """The shape (module docstring) of ``node``; a tuple inside a comparison counts as the
    comparison, and the right side of ``a, b = x, y`` is not a tuple of anything."""
    if isinstance(node, ast.Compare):
        return "compare" if any(_ids_in(side) for side in (node.left, *node.comparators)) else None
    if isinstance(node, ast.Dict):  # keyed by the ids themselves (a key (sensor, field) is a file's field)
        keys = [k for k in node.keys if isinstance(k, ast.Constant)]
        return "table" if sum(1 for k in keys if _ids_in(k)) >= 2 else None
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)) and not not_a_table:
        return "table" if len(_ids_in(node)) >= 2 else None
    if isinstance(node, ast.MatchValue):
        return "compare" if _ids_in(node.value) else None
    if isinstance(node, ast.Subscript):
        return "pick" if _ids_in(node.slice) else None
    if isinstance(node, ast.Call) and getattr(node.func, "attr", "") in ("get", "pop") and node.args:
        return "pick" if _ids_in(node.args[0]) else None
    return None


def name_uses(path: Path, root: Path = ROOT) -> list[tuple[str, str, str]]:
    """``(kind, "file:line", source)`` of every use of a term id in ``path`` that the module docstring counts."""
    text = path.read_text()
    if not any(f'"{n}"' in text or f"'{n}'" in text for n in IDS):  # no id: nothing to parse
        return []
    tree = ast.parse(text, filename=str(path))
    not_a_table = {id(c) for n in ast.walk(tree) if isinstance(n, ast.Compare) for c in (n.left, *n.comparators)}
    not_a_table |= {id(n.value) for n in ast.walk(tree)
                    if isinstance(n, ast.Assign) and isinstance(n.targets[0], ast.Tuple)}
    out = []
    for node in ast.walk(tree):
        kind = _kind(node, id(node) in not_a_table)
        if kind:
            out.append((kind, f"{path.relative_to(root).as_posix()}:{node.lineno}", ast.unparse(node)))
    return out


def sources(root: Path = ROOT) -> list[Path]:
    table = root / "src" / "accelcal" / "noise" / "terms.py"
    return sorted(p for p in (root / "src" / "accelcal").rglob("*.py") if p != table)


@functools.lru_cache(maxsize=None)
def all_uses(root: Path = ROOT) -> tuple[tuple[str, str, str], ...]:
    """Every counted use in ``root``'s ``src/accelcal`` (parsed once for both tests)."""
    return tuple(u for p in sources(root) for u in name_uses(p, root))


def unexplained(root: Path = ROOT) -> list[tuple[str, str, str]]:
    return [u for u in all_uses(root) if (u[1].rsplit(":", 1)[0], u[2]) not in ALLOWED]


def test_no_module_branches_on_a_noise_term_id():
    assert unexplained() == []


def test_every_allowed_use_still_exists_and_says_why():
    """An entry of ALLOWED whose code is gone is removed with it (the list says what is left)."""
    seen = {(u[1].rsplit(":", 1)[0], u[2]) for u in all_uses()}
    assert all(isinstance(why, str) and len(why) > 30 for why in ALLOWED.values())
    assert sorted(set(ALLOWED) - seen) == []


def test_the_check_sees_the_old_branches(tmp_path):
    old = tmp_path / "src" / "accelcal" / "old.py"
    old.parent.mkdir(parents=True)
    old.write_text(
        'UNITS = {"white": "{u}/sqrt(Hz)", "random_walk": "{w}"}\n'
        'IEEE = ("quantization", "white", "bias_instability")\n'
        'def f(term, terms, d):\n'
        '    far = 0.7 ** d if term in ("random_walk", "drift_ramp") else 1.0\n'
        '    for k in ("bias_instability", "random_walk"):\n'
        '        pass\n'
        '    n = terms["white"].value\n'
        '    q = terms.get("quantization", 0.0)\n'
        '    match term:\n'
        '        case "sinusoid":\n'
        '            pass\n'
        '    x = " (the exports use it)" if term == "random_walk" else ""\n'
        '    model = {"white": 0.01}\n'
        '    used = fit(("white",), noise_term("gauss_markov"))\n')
    kinds = sorted(k for k, _, _ in name_uses(old, tmp_path))
    assert kinds == ["compare", "compare", "compare", "pick", "pick", "table", "table", "table"], kinds
