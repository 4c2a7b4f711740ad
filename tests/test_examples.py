"""The examples of docs/extending.md run, and the page shows their code.

Each script in ``examples/`` adds an estimator, an effect or a file format at run time and
uses it end to end; here each runs in a fresh process (they change the registries) and
must succeed and print what it did.  Every code block of the page is an excerpt of one
of the scripts, every file the page names exists, and the example's estimator passes the
conformance checks every registered estimator passes.
"""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from accelcal.discrepancy.wander import MEMBERS, unregister_member
from accelcal.discrepancy.wander_process import PROCESSES, unregister_process
from accelcal.errors import RecordingError
from accelcal.formats import read
from accelcal.noise.terms import TERMS, unregister_term
from accelcal.registry import ESTIMATORS, register, unregister

from .format_samples import RATE_HZ, SAMPLES, specific_force
from .test_estimator_conformance import CHECKS, run_check
from .test_noise_term_conformance import CHECKS as TERM_CHECKS
from .test_wander_member_conformance import CHECKS as MEMBER_CHECKS
from .test_wander_process_conformance import CHECKS as PROCESS_CHECKS
from .test_reader_fuzz import _check_recording, damaged_files

REPO = Path(__file__).resolve().parents[1]
EXAMPLES = REPO / "examples"
PAGE = REPO / "docs" / "extending.md"


def _run(name: str, tmp_path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(EXAMPLES / name)], capture_output=True, text=True, cwd=tmp_path,
                          timeout=600)


def test_the_estimator_example_calibrates_from_the_command_line(tmp_path):
    p = _run("custom_estimator.py", tmp_path)
    assert p.returncode == 0, p.stderr
    assert p.stderr.startswith("bias-gn: 16 poses (noise reference: initial rest")  # the CLI's summary names it
    assert re.match(r"BiasGNCalibration: bias \[.*\] after \d+ iterations", p.stdout), p.stdout


def test_the_effect_example_names_and_inverts_the_effect(tmp_path):
    p = _run("custom_effect.py", tmp_path)
    assert p.returncode == 0, p.stdout + p.stderr
    assert p.stdout.startswith("discrepancy: 60 poses; effect named: quartic\n")
    assert re.search(r"apply: largest error \S+ m/s\^2 over 60 rests \(\S+ without the effect\)", p.stdout)


def test_the_format_example_is_detected_and_calibrated(tmp_path):
    p = _run("custom_format.py", tmp_path)
    assert p.returncode == 0, p.stderr
    assert p.stdout.startswith("detected as xyz-log; ")
    assert "  read: format: xyz-log (detected; pass --format to choose another)" in p.stderr.splitlines()


def _code_blocks(text: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


def test_every_code_block_of_the_page_is_in_an_example():
    scripts = [p.read_text() for p in sorted(EXAMPLES.glob("*.py"))]
    blocks = _code_blocks(PAGE.read_text())
    assert len(blocks) >= 6
    missing = [b for b in blocks if not any(b in s for s in scripts)]
    assert not missing, "code on the page that no example runs:\n" + "\n".join(missing)


def test_the_check_of_code_blocks_sees_a_block_no_example_has():
    text = "intro\n```python\nENTRY = Format(name='nowhere')\n```\n"
    assert _code_blocks(text) == ["ENTRY = Format(name='nowhere')\n"]
    assert not any(_code_blocks(text)[0] in p.read_text() for p in EXAMPLES.glob("*.py"))


def test_every_file_the_page_names_exists():
    names = set(re.findall(r"`((?:src|tests|workflow|config|examples|docs)/[\w./-]+)`", PAGE.read_text()))
    assert len(names) >= 10
    assert sorted(n for n in names if not (REPO / n).exists()) == []


def _example_module(name: str):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # the entry names its function as 'custom_estimator:bias_gn'
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def example_estimator():
    module = _example_module("custom_estimator")
    register(module.ENTRY)
    yield ESTIMATORS[module.ENTRY.name]
    unregister(module.ENTRY.name)
    sys.modules.pop("custom_estimator", None)


@pytest.mark.parametrize("check", CHECKS, ids=lambda c: c.__name__.removeprefix("check_"))
def test_the_example_estimator_passes_every_conformance_check(example_estimator, check, tmp_path):
    run_check(check, example_estimator, tmp_path)


def test_the_noise_term_example_fits_its_term(tmp_path):
    p = _run("custom_noise_term.py", tmp_path)
    assert p.returncode == 0, p.stderr
    m = re.match(r"telegraph: A = (\S+) \(true 0.05\), dwell time (\S+) s \(true 4 s\)", p.stdout)
    assert m and abs(float(m[1]) / 0.05 - 1) < 0.15 and abs(float(m[2]) / 4 - 1) < 0.3, p.stdout


@pytest.fixture(scope="module")
def example_term():
    module = _example_module("custom_noise_term")  # registers the term on import
    yield TERMS["telegraph"]
    unregister_term("telegraph")
    sys.modules.pop("custom_noise_term", None)


@pytest.mark.parametrize("check", TERM_CHECKS, ids=lambda c: c.__name__.removeprefix("check_"))
def test_the_example_noise_term_passes_every_conformance_check(example_term, check):
    check(example_term)


def test_the_wander_process_example_names_and_reads_its_process(tmp_path):
    p = _run("custom_wander_process.py", tmp_path)
    assert p.returncode == 0, p.stderr
    lines = p.stdout.splitlines()
    assert lines[0] == "process: unresolved_wander (wander of unknown time scale)", p.stdout
    assert lines[1].startswith("reading: noise between the poses of 0.00182 data unit per axis, time scale not")
    assert lines[2] == "simulated as: (('gauss_markov', (0.001821, 5.967)),)", p.stdout


@pytest.fixture(scope="module")
def example_process():
    _example_module("custom_wander_process")  # registers the process on import
    yield PROCESSES["unresolved_wander"]
    unregister_process("unresolved_wander")
    sys.modules.pop("custom_wander_process", None)


@pytest.mark.parametrize("check", PROCESS_CHECKS, ids=lambda c: c.__name__.removeprefix("check_"))
def test_the_example_wander_process_passes_every_conformance_check(example_process, check):
    check(example_process)


def test_the_grid_member_example_is_named_on_a_drifting_session(tmp_path):
    p = _run("custom_grid_member.py", tmp_path)
    assert p.returncode == 0, p.stderr
    lines = p.stdout.splitlines()
    assert lines[0].startswith("rate 2e-05: grid of 26 codes, drift_rate's among them: True; REML named: drift_rate"), p.stdout
    assert lines[2] == "in one_process's grid: False", p.stdout


@pytest.fixture(scope="module")
def example_member():
    _example_module("custom_grid_member")  # registers the member and its process on import
    yield MEMBERS["drift_rate"], PROCESSES["drift_rate"]
    unregister_process("drift_rate")
    unregister_member("drift_rate")
    sys.modules.pop("custom_grid_member", None)


@pytest.mark.parametrize("check", MEMBER_CHECKS, ids=lambda c: c.__name__.removeprefix("check_"))
def test_the_example_grid_member_passes_every_conformance_check(example_member, check):
    check(example_member[0])


@pytest.mark.parametrize("check", PROCESS_CHECKS, ids=lambda c: c.__name__.removeprefix("check_"))
def test_the_example_grid_members_process_passes_every_conformance_check(example_member, check):
    check(example_member[1])


@pytest.fixture()
def example_format():
    module = _example_module("custom_format")
    from accelcal.formats import FORMATS

    FORMATS[module.ENTRY.name] = module.ENTRY
    yield module
    FORMATS.pop(module.ENTRY.name, None)
    sys.modules.pop("custom_format", None)


@pytest.mark.parametrize("body, cause", [
    ("0 0 1\n", "only 1 data rows; need at least 10"),
    ("0 0 1\n" * 11 + "nan 0 1\n", "non-finite value nan at line 13"),
])
def test_the_example_reader_needs_no_checks_of_its_own(example_format, tmp_path, body, cause):
    """The recording's invariants are checked where every reader's output passes (formats.read): the
    guide's reader, which checks neither row count nor finiteness, still gives one line."""
    path = tmp_path / "short.txt"
    path.write_text(f"{example_format.MAGIC} 100 Hz\n{body}")
    with pytest.raises(RecordingError, match=cause) as e:
        read(path)
    assert "\n" not in str(e.value)


@pytest.fixture()
def fuzzed_example_format(example_format):
    """The guide's reader registered, with a sample file the fuzz damages (as tests/format_samples.py has one per format)."""
    def sample(rng) -> bytes:
        acc = specific_force(rng, scale=1.0)
        return (f"{example_format.MAGIC} {RATE_HZ:g} Hz\n"
                + "".join(f"{x:.6g} {y:.6g} {z:.6g}\n" for x, y, z in acc)).encode()

    SAMPLES[example_format.ENTRY.name] = sample
    yield example_format.ENTRY.name
    SAMPLES.pop(example_format.ENTRY.name, None)


@st.composite
def xyz_logs(draw) -> bytes:
    """Well-formed xyz-log files of few rows and any float (nan, inf, huge): what the reader itself never checks."""
    value = st.floats(allow_nan=True, allow_infinity=True) | st.sampled_from([0.0, 1.0, -1.0])
    rows = draw(st.lists(st.tuples(value, value, value), max_size=15))
    rate = draw(st.sampled_from([100.0, 1e-300, 1e300]))
    return (f"# xyz-log {rate:g} Hz\n" + "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in rows)).encode()


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_the_example_reader_passes_the_reader_fuzz(fuzzed_example_format, data, tmp_path):
    """The reader fuzz's property on the guide's reader, which checks neither row count nor
    finiteness nor time itself: damaged files (tests/test_reader_fuzz.py's, and short files
    of any float) give a valid Recording or one RecordingError line."""
    path = tmp_path / "rec.txt"
    path.write_bytes(data.draw(damaged_files(fuzzed_example_format) | xyz_logs()))
    try:
        rec = read(path, format=fuzzed_example_format)
    except RecordingError as e:
        assert str(e) and "\n" not in str(e)
    else:
        _check_recording(rec, fuzzed_example_format, False)
