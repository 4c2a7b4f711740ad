"""Workflow config per key (pypsa-eur's config_provider; ``common.smk``'s ``config_keys``):
no rule's ``params`` holds a stage's whole config section, so that ``--rerun-triggers
params`` reruns a job only when a key its code reads changes (tests/test_workflow_reruns.py
checks it on the CI run for three stages' claim thresholds).  The rule files are read as
text: a param whose value is ``config["stage"]``, or a module-level name bound to it
(``MAG = config["mag"]``), is a whole section.  A sub-section the code reads as one group
(``rules=DISCREPANCY["rules"]``: every key builds the detection rules) is per key."""

from __future__ import annotations

import re
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[1]
RULES = REPO / "workflow" / "rules"

#: Rules still given a whole section, in parts being worked on now: may only shrink.
NOT_YET: set = set()  # every rule reads its keys now (the gyro stage's six were the last)

_SECTION = re.compile(r'^([A-Z][A-Z0-9_]*)\s*=\s*((?:config|[A-Z][A-Z0-9_]*)(?:\["[^"]+"\])+)\s*$', re.M)
_RULE = re.compile(r"^rule (\w+):\n((?:[ \t].*\n|\n)*)", re.M)
_PARAMS = re.compile(r"^    params:\n((?:        .*\n)*)", re.M)
_PARAM = re.compile(r"^\s+(\w+)=((?:config|[A-Z][A-Z0-9_]*)(?:\[\"[^\"]+\"\])*),?\s*(?:#.*)?$")


def _value(expr: str, names: dict[str, str], config: dict):
    """The config value an expression such as ``config["a"]["b"]`` or ``NAME["b"]`` stands for."""
    head, *keys = re.findall(r'^\w+|(?<=\[")[^"]+(?="\])', expr)
    if head != "config":
        if head not in names:
            return None
        return _value(names[head] + "".join(f'["{k}"]' for k in keys), names, config)
    value = config
    for k in keys:
        value = value.get(k) if isinstance(value, dict) else None
    return value


def _depth(expr: str, names: dict[str, str]) -> int:
    """How many keys below ``config`` an expression reaches (``MAG["loop"]``: 2)."""
    head, *keys = re.findall(r'^\w+|(?<=\[")[^"]+(?="\])', expr)
    return len(keys) + (0 if head == "config" else _depth(names[head], names) if head in names else 99)


def whole_sections(rules_dir: Path, config: dict) -> set[tuple[str, str]]:
    """``(rule, param)`` of every param in ``rules_dir/*.smk`` that holds a stage's whole config section."""
    texts = [p.read_text() for p in sorted(rules_dir.glob("*.smk"))]
    names = {m.group(1): m.group(2) for t in texts for m in _SECTION.finditer(t)}
    found = set()
    for text in texts:
        for rule in _RULE.finditer(text):
            params = _PARAMS.search(rule.group(2))
            for line in params.group(1).splitlines() if params else []:
                m = _PARAM.match(line)
                if m and _depth(m.group(2), names) == 1 and isinstance(_value(m.group(2), names, config), dict):
                    found.add((rule.group(1), m.group(1)))
    return found


def test_no_rule_takes_a_whole_config_section():
    config = yaml.safe_load((REPO / "config" / "config.yaml").read_text())
    found = whole_sections(RULES, config)
    assert found - NOT_YET == set(), "give the rule config_keys(SECTION, ...) of the keys its code reads"
    assert NOT_YET - found == set(), "now per key: take them out of NOT_YET"


def test_the_check_sees_a_whole_section(tmp_path):
    (tmp_path / "a.smk").write_text(
        'MAG = config["mag"]\nLOOP = MAG["loop"]\n\n\nrule one:\n    params:\n        mag=MAG,\n        loop=LOOP,\n'
        '        seed=MAG["seed"],\n        keys=config_keys(MAG, "seed"),\n    script:\n        "x.py"\n\n\n'
        'rule two:\n    params:\n        m=config["mag"]["loop"],\n        whole=config["mag"],\n')
    config = {"mag": {"seed": 1, "loop": {"n": 2}}}
    assert whole_sections(tmp_path, config) == {("one", "mag"), ("two", "whole")}
