"""What users read speaks of the project only: no issue numbers (development history belongs
in commit messages) in the library, the workflow, the config, the README, and the figure and
report texts drawn from them (the report and ledger of a CI run: tests/test_workflow_structure.py)."""

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
#: "issue 13", "Issue 7's", "issues 7 and 13", "issue #8".
ISSUE_NUMBER = re.compile(r"\bissues?[\s-]+#?\d+", re.IGNORECASE)
#: Where user-facing text comes from: docstrings, comments, labels, captions, conclusions,
#: claim statements, config comments, rule docs.
SOURCES = ("src", "workflow", "config")


def issue_numbers(text: str) -> list[str]:
    """The issue-number mentions in ``text``, with the line number of each."""
    return [f"{text.count(chr(10), 0, m.start()) + 1}: {m.group(0)}" for m in ISSUE_NUMBER.finditer(text)]


def _text_files():
    files = [REPO / "Snakefile", REPO / "README.md"]
    for folder in SOURCES:
        files += [p for p in sorted((REPO / folder).rglob("*")) if p.is_file() and "__pycache__" not in p.parts]
    return files


def test_the_check_sees_issue_numbers():
    text = 'label="wander null (issue 13)"\n# Issues 7 and 13: the loop\nsee issue #8\n'
    assert issue_numbers(text) == ["1: issue 13", "2: Issues 7", "3: issue #8"]
    assert issue_numbers("a tissue 3 cm wide; an open issue; issue-free") == []


def test_no_issue_numbers_in_sources_figures_and_report_texts():
    files = _text_files()
    assert len(files) > 150 and any(p.suffix == ".rst" for p in files)
    found = [f"{p.relative_to(REPO)}:{hit}" for p in files for hit in issue_numbers(p.read_text(errors="replace"))]
    assert not found, "issue numbers in what users read: " + "; ".join(found)
