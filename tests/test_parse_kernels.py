"""The compiled table parser (formats/_parse_kernels.py) reads Python's ``float`` of each field,
bit for bit, and gives up (None) on everything it cannot read exactly, which pandas then reads."""

import numpy as np
import pytest

from accelcal import kernels
from accelcal.formats import numeric_block

pytest.importorskip("numba")
K = kernels.compiled("formats._parse_kernels")
pytestmark = pytest.mark.skipif(K is None, reason="compiled kernels switched off (ACCELCAL_KERNELS=numpy)")


def _fields(rng, n):
    """Plain decimal fields of every shape the parser takes: signs, leading zeros, no integer or
    no fraction part, exponents, -0, up to 15 significant digits, powers of ten up to ±22."""
    out = []
    for _ in range(n):
        digits = "".join(rng.choice(list("0123456789"), size=rng.integers(1, 16)))
        point = rng.integers(0, len(digits) + 1)
        body = digits[:point] + "." + digits[point:] if rng.random() < 0.8 else digits
        sign = rng.choice(["", "-", "+"], p=[0.6, 0.3, 0.1])
        exp = "" if rng.random() < 0.7 else f"{rng.choice(['e', 'E'])}{rng.choice(['', '+', '-'])}{rng.integers(0, 8)}"
        out.append(sign + body + exp if body != "." else "0")
    return out + ["-0", "-0.0", "0.0", ".5", "5.", "-.25e1", "1e22", "123456789012345e-22"]


@pytest.mark.parametrize("delim,sep,eol", [(",", ",", "\n"), (";", " ; ", "\r\n"), ("\t", "\t", "\n"),
                                          (" ", "  \t ", "\n"), ("|", "|", "\r\n")])
def test_the_same_bits_as_python_float(delim, sep, eol):
    rng = np.random.default_rng(len(sep))
    k = 3
    f = _fields(rng, 3 * 400)
    n = len(f) // k
    lines = [sep.join(f[k * i: k * i + k]) for i in range(n)]
    if delim == " ":
        lines = ["  " + ln + " " for ln in lines]  # blanks around a whitespace table's lines
    text = eol.join(lines)
    cut = text.find("\n", len(text) // 2) + 1  # two pieces, the first ending after a line feed
    got = K.parse_lines([text[:cut].encode(), text[cut:].encode()], delim, k, n)
    want = np.array([float(x) for x in f[:n * k]]).reshape(n, k).T
    assert got is not None
    assert np.array_equal(np.array(got).view(np.int64), want.view(np.int64))


@pytest.mark.parametrize("text", ["1,2\n3", "1,2\n3,4,5", "1,2\n\n3,4", "1,2\r3,4", "1,,2\n3,4", "1,2,\n3,4",
                                  "1,nan\n3,4", "1,inf\n3,4", "1,0x10\n3,4", "1,2e\n3,4", "1,-\n3,4", "1,\"2\"\n3,4",
                                  "0.12345678901234567,2\n3,4", "1e23,2\n3,4", "1e-23,2\n3,4", "1_0,2\n3,4",
                                  "1,2 3\n4,5"])
def test_gives_up_on_what_it_cannot_read_exactly(text):
    assert K.parse_lines([text.encode()], ",", 2, 2) is None


def test_a_large_block_reads_as_pandas_reads_it(monkeypatch):
    """parse_block's compiled route (a block from the size that pandas would read) against
    pandas' route on the same text; and a field it gives up on goes to pandas, same numbers."""
    rng = np.random.default_rng(1)
    x = np.round(rng.normal(size=(3000, 4)) * 10.0 ** rng.integers(-3, 4, size=(3000, 4)), 5)
    text = "a,b,c,d\n" + "\n".join(",".join(repr(float(v)) for v in row) for row in x) + "\n"
    monkeypatch.setattr(numeric_block, "_PANDAS_FROM_CHARS", 100)
    monkeypatch.setattr(numeric_block, "_PIECE_CHARS", 1000)
    compiled, _ = numeric_block.parse_block(text, 8, ",", 4)
    monkeypatch.setattr(numeric_block, "_compiled_columns", lambda *a: None)
    pandas, _ = numeric_block.parse_block(text, 8, ",", 4)
    assert np.array_equal(np.array(compiled).view(np.int64), np.array(pandas).view(np.int64))
    assert np.array_equal(np.array(compiled), x.T)
    monkeypatch.undo()
    assert numeric_block._compiled_columns(numeric_block.Body(text + "é", 8, len(text) + 1), ",", 4, 3000) is None
