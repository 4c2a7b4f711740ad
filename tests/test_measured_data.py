"""accelcal_repro.measured.data: shared copy, verified download (file:// URLs), checksum and network failures."""

from __future__ import annotations

import hashlib
import re
import urllib.error
import urllib.request
from pathlib import Path

import pytest

from accelcal.errors import AccelcalError
from accelcal_repro.measured import data as md
from accelcal.atomic import sha256_file
from accelcal_repro.measured.data import DATASETS, DatasetError, fetch_file
from accelcal_repro.measured.sources import SOURCES, fetch_source

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
needs_data = pytest.mark.skipif(not DATA.is_dir(), reason="shared/data not available")


def _payload(tmp_path, content=b"t x y z\n0 1 2 3\n"):
    src = tmp_path / "upstream" / "file.bin"
    src.parent.mkdir()
    src.write_bytes(content)
    return src, hashlib.sha256(content).hexdigest()


def test_download_from_file_url_is_verified_and_atomic(tmp_path):
    src, sha = _payload(tmp_path)
    res = tmp_path / "resources"
    p = fetch_file("imu_tk_xsens", "xsens_acc.mat", data_dir=tmp_path / "no_shared", resources_dir=res,
                   url=src.as_uri(), sha256=sha)
    assert p == res / "imu_tk_xsens" / "xsens_acc.mat"
    assert p.read_bytes() == src.read_bytes()
    assert [f.name for f in p.parent.iterdir()] == ["xsens_acc.mat"]  # no .part left behind
    # second call: the verified local copy is reused, no download
    src.unlink()
    assert fetch_file("imu_tk_xsens", "xsens_acc.mat", None, res, url=src.as_uri(), sha256=sha) == p


def test_download_with_wrong_checksum_leaves_nothing(tmp_path):
    src, sha = _payload(tmp_path)
    res = tmp_path / "resources"
    with pytest.raises(DatasetError, match="does not match") as e:
        fetch_file("imu_tk_xsens", "xsens_acc.mat", None, res, url=src.as_uri(), sha256="0" * 64)
    assert "\n" not in str(e.value)
    assert not any((res / "imu_tk_xsens").iterdir())  # neither the file nor a partial one


def test_damaged_shared_copy_is_an_error_not_replaced(tmp_path):
    shared = tmp_path / "shared"
    (shared / "imu_tk_xsens").mkdir(parents=True)
    (shared / "imu_tk_xsens" / "xsens_acc.mat").write_bytes(b"damaged")
    src, sha = _payload(tmp_path)
    with pytest.raises(DatasetError, match="damaged or different shared copy"):
        fetch_file("imu_tk_xsens", "xsens_acc.mat", shared, tmp_path / "res", url=src.as_uri(), sha256=sha)
    assert not (tmp_path / "res").exists()


def test_stale_download_is_reported(tmp_path):
    src, sha = _payload(tmp_path)
    res = tmp_path / "res" / "imu_tk_xsens"
    res.mkdir(parents=True)
    (res / "xsens_acc.mat").write_bytes(b"old")
    with pytest.raises(DatasetError, match="delete it to download again"):
        fetch_file("imu_tk_xsens", "xsens_acc.mat", None, tmp_path / "res", url=src.as_uri(), sha256=sha)


def test_missing_dataset_without_network_is_one_clear_line(tmp_path, monkeypatch):
    def offline(*a, **k):
        raise urllib.error.URLError("[Errno -3] Temporary failure in name resolution")

    monkeypatch.setattr(urllib.request, "urlopen", offline)
    with pytest.raises(DatasetError) as e:
        fetch_source("mpu6050", data_dir=tmp_path / "nowhere", resources_dir=tmp_path / "res")
    msg = str(e.value)
    assert "\n" not in msg and isinstance(e.value, AccelcalError)
    assert "no shared copy at" in msg and "raw.githubusercontent.com/tomisuarez2" in msg
    assert f"copy the dataset folder into {tmp_path / 'nowhere' / 'mpu6050_suarez'}" in msg and "network access" in msg
    assert "name resolution" in msg
    assert not list((tmp_path / "res").rglob("*.part"))


def test_unknown_file_is_a_typed_error():
    with pytest.raises(DatasetError, match="unknown measured file"):
        md.spec("imu_tk_xsens", "nope.mat")


def test_urls_are_pinned_to_the_readme_commits():
    for dataset, files in DATASETS.items():
        for f, s in files.items():
            assert re.fullmatch(r"https://raw\.githubusercontent\.com/[\w.-]+/[\w.-]+/[0-9a-f]{40}/\S+", s.url), s.url
            assert s.url.endswith(f.replace(" ", "%20")) and re.fullmatch(r"[0-9a-f]{64}", s.sha256)
    assert "calibration%20data/example_data_calibration.csv" in DATASETS["mpu6050_suarez"][
        "example_data_calibration.csv"].url


@needs_data
def test_table_matches_the_data_readme():
    """Every sha256 in shared/data/README.md is in the table, for the same file."""
    readme = (DATA / "README.md").read_text()
    rows = dict(re.findall(r"^\| (\S+) \| ([0-9a-f]{64}) \|$", readme, flags=re.M))
    table = {f: s.sha256 for files in DATASETS.values() for f, s in files.items()}
    assert rows == table
    # the commits of the sources (a "- Source:" item and its continuation lines), not of
    # references quoted elsewhere (the factory values' MATLAB port)
    sources = " ".join(m.replace("\n", " ") for m in re.findall(r"^- Source:.*?(?=^- |^#|\Z)", readme, flags=re.M | re.S))
    commits = set(re.findall(r"commit\s+`?([0-9a-f]{40})", sources))
    pinned = {re.search(r"/([0-9a-f]{40})/", s.url).group(1) for files in DATASETS.values() for s in files.values()}
    assert commits == pinned


@needs_data
def test_shared_copies_are_used_and_verified(tmp_path):
    for name in SOURCES:
        paths = fetch_source(name, DATA, tmp_path / "res")
        for f, p in paths.items():
            assert p == DATA / SOURCES[name].dataset / f and p.is_file()  # the shared copy itself
            assert sha256_file(p) == DATASETS[SOURCES[name].dataset][f].sha256
    assert not (tmp_path / "res").exists()  # nothing downloaded, nothing copied
