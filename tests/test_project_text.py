"""What users read speaks of the project only: no issue numbers (development history belongs
in commit messages) in the library, the workflow, the config, the README, and the figure and
report texts drawn from them (the report and ledger of a CI run: tests/test_workflow_structure.py)."""

import re
import shutil
import subprocess
from pathlib import Path

import pytest

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


#: Commit subjects are short from this commit on (git's 72-character convention, details in the
#: body); the history before it is left as it was written.
SHORT_SUBJECTS_SINCE = "f8334dc"


def long_subjects(log: str, limit: int = 72) -> list[str]:
    """The lines of ``git log --format='%h %s'`` whose subject is longer than ``limit``."""
    return [line for line in log.splitlines() if len(line.partition(" ")[2]) > limit]


def test_the_subject_check_sees_a_long_subject():
    assert long_subjects("abc1234 short\ndef5678 " + "x" * 73) == ["def5678 " + "x" * 73]


def test_commit_subjects_are_at_most_72_characters():
    if shutil.which("git") is None or not (REPO / ".git").exists():
        pytest.skip("not a git checkout: no history to check")
    known = subprocess.run(["git", "-C", str(REPO), "cat-file", "-e", SHORT_SUBJECTS_SINCE + "^{commit}"],
                           capture_output=True)
    if known.returncode:
        pytest.skip(f"history before {SHORT_SUBJECTS_SINCE} absent (shallow clone)")
    log = subprocess.run(["git", "-C", str(REPO), "log", "--format=%h %s", f"{SHORT_SUBJECTS_SINCE}..HEAD"],
                         capture_output=True, text=True, check=True).stdout
    assert long_subjects(log) == []
