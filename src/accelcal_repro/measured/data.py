"""Getting the measured recordings: the shared copy if present, else a verified download.

The public recordings (``shared/data/README.md``) are inputs, never part of the
repository.  :func:`fetch_file` returns a local path for one file of one dataset:

1. ``<data_dir>/<dataset>/<file>`` (the shared copy, ``../shared/data`` from the project
   root) if it exists; its sha256 must match :data:`DATASETS`, else
   :class:`DatasetError` (a damaged shared copy is reported, not silently replaced);
2. else ``<resources_dir>/<dataset>/<file>`` if an earlier download left it there and it
   verifies;
3. else a download from the pinned public URL with :mod:`urllib` into a temporary file
   beside the target, verified, then renamed (atomic: a reader sees no file or the whole
   verified file, never part of one).

Every failure (no shared copy and no network, a checksum mismatch) is one
:class:`DatasetError` with a one-line message that says what to do.  In the workflow the
fetch is a job of its own (rules ``measured_fetch``, ``discrepancy_adis_fetch``), run
first, so that a missing dataset stops a run before the long jobs and stages that do not
need the data run without it.  URLs point at fixed commits, so a verified download is
byte-identical to the shared copy.
"""

from __future__ import annotations

import hashlib
import http.client
import os
import urllib.request
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import quote

from accelcal.atomic import atomic_output, sha256_file
from accelcal.errors import AccelcalError


class DatasetError(AccelcalError):
    """A measured dataset that cannot be found, downloaded or verified."""


@dataclass(frozen=True)
class FileSpec:
    """One public file: where it comes from and its sha256."""

    url: str
    sha256: str


def _raw(repo: str, commit: str, path: str) -> str:
    return f"https://raw.githubusercontent.com/{repo}/{commit}/{quote(path)}"


_XSENS = ("Kyle-ak/imu_tk", "7780270fb9a227c79323199303f23989e689a89d")
_IMUCAL = ("mad-lab-fau/imucal", "8716e4c50bbb7044918b747f38b26cb0a6420910")
_MPU = ("tomisuarez2/ImuCalibration", "c86ea2531da0da7929b884b52d8955c0ea0615ff")
_FORK = ("GetOverMassif/imu_tk", "92022128c1dad9d7ef7f46d6d82b0d9a10a58e22")
_FASTAHRS_1 = ("vspruyt/FastAhrs", "62347ae9d6c1c7531939da5535ed6a9a79769c33")
_FASTAHRS_2 = ("vspruyt/FastAhrs", "b7016d56b13aa405cfbc7bdf145201879f0336ee")
_SMAC = ("SMAC-Group/imudata", "dd603068355f2dfa757a474645cd327c5cb6dbb5")
_CTU = ("labliscvut/imu_calibration", "053aa5d56669c115fba484ea119e50af8ddc1e79")
_SNU = ("ChanghyeonKim93/IMU_calibration_staticposes", "468a3dc3db1575a73222128461b1c19e565bd377")
_PYULOG = ("PX4/pyulog", "3cf17793f14709713ab297d3743314c658874068")
_CK = ("CK-Explorer/Magnetometer-and-Accelerometer-Calibration", "61ac7669f1cbba2e5ce77763a40ebc123d95ac60")
_QMC = ("tomisuarez2/MagnetometerCalibration", "eb93f820ffc06155579b7d86928795915eef714a")
_FORK_SHA256 = {
    "data1/acc_data.txt": "d1fc1ad4b19bde88c2cdd6aee4a852e32399d8acbd9bcbbc24157e4c13a385d8",
    "data1/gyro_data.txt": "a97e7fe4334c0012581dd77888c988050494b7a75715a81756bc839a0abe5739",
    "data1/rosbag2_2023_08_11-21_37_35/metadata.yaml": "f94142d182f8c688ffdba071ab39cc58cfb8a10212f66d0af0c935333f733667",
    "data1/rosbag2_2023_08_11-21_37_35/rosbag2_2023_08_11-21_37_35_0.db3": "8fea2b3cd5bb88053b4e67ddceb42fb8b372df27cb181d4b3d53b649c5923fa2",
    "data1/test_imu_acc.calib": "6963b532efa2db9506f37ed68f67710718676ee78089dfd7185da332b3ff4259",
    "data1/test_imu_gyro.calib": "7008122559c7463bb7c0291c8e57d74c1637a728fa9f49817e4c5ab0137fad2d",
    "data2/acc_data.txt": "f621b1fa75d327acdadac6e506aa416466d4290f4db209c80651e6cee7482bd3",
    "data2/gyro_data.txt": "9c83d1b7864f7df3f1dd34d24875bce9485596d70911b6a9ad915c5b813ae54f",
    "data2/test_imu_acc.calib": "86cca43ece5c1623f58c4a83659c492b3b1516506343261128bd45ebe83d31e8",
    "data2/test_imu_gyro.calib": "44b5613d795dfa91e3f8ec0325b2b91ce0aa53d1e4267f635c2a5937661602da",
    "data3/acc_data.txt": "b908e8626ac1c2df61638b1c7a54e1cc346f584473707c17928c22140d4f40c5",
    "data3/gyro_data.txt": "94b02855ce68f757d1d2eb23a6c5655ccc2812e21b676e38cd39b015524f1333",
    "data3/test_imu_acc.calib": "1d770b8ee9ecf698439b267080bcfa4769dceee6a203fa35da8e85b4a1389c97",
    "data3/test_imu_gyro.calib": "e871129d543bc8d4fc8a13d812eaba6937f27ea98bc7b6ed19263e1dcc68656a",
    "data4/acc_data.txt": "1719259ab4282c263cbc2a27f49532d724adc00736fa560cc9b06d8addc11b73",
    "data4/gyro_data.txt": "28c766723cd680661c81e8590c8dc6b06aea61d6536ff2aa38dceaaea8fb0411",
    "data4/test_imu_acc.calib": "ce302f293e1f6876abea410222a822bd9ea0ca2e06b4556a49f6247a5fad08cf",
    "data4/test_imu_gyro.calib": "a6e6d88176111f0a846d7e68a9468ff0ef6f4884ef8db8b36864bf815faa9862",
    "data_sample.csv": "29d9fc9eca89152280d0158c969dd4a74d33f2e9e7e94e2c50747e1a4bc503ee",
    "data_sample2.csv": "c6f068238e402991238935f3173a5815d77484a9ade15dc9200810a48c294428",
}

#: ``{dataset: {file: FileSpec}}``, from ``shared/data/README.md`` (source, commit, sha256).
DATASETS: dict[str, dict[str, FileSpec]] = {
    "imu_tk_xsens": {
        "xsens_acc.mat": FileSpec(_raw(*_XSENS, "bin/test_data/xsens_acc.mat"),
                                  "335a234736ff4dd8741118283d5d4cd389ac54b04d00e6cd8d48ca3e532b7510"),
        "xsens_gyro.mat": FileSpec(_raw(*_XSENS, "bin/test_data/xsens_gyro.mat"),
                                   "e0d6cc7ccbc996aba3dae5063e97360a8b765ad1dffd02eae8ec69820eb37c1d"),
    },
    "imucal_ferraris": {
        "example_ferraris_session.csv": FileSpec(
            _raw(*_IMUCAL, "example_data/example_ferraris_session.csv"),
            "18a3b4f83b9526bc9ce9c32461c4e7c787ea239596ad091ce0d293662c0aae3d"),
        "example_ferraris_session_list.json": FileSpec(
            _raw(*_IMUCAL, "example_data/example_ferraris_session_list.json"),
            "d21e4170b7918ea05d8fa6f247d694250275f42ede28224535c328dad1ca8ace"),
        "annotated_session.csv": FileSpec(
            _raw(*_IMUCAL, "example_data/annotated_session.csv"),
            "bd4b8f3b4b270d76327523d886d9b056c3b6da405420824b62267fbce30379ff"),
    },
    "mpu6050_suarez": {
        "example_data_calibration.csv": FileSpec(
            _raw(*_MPU, "calibration data/example_data_calibration.csv"),
            "e6185b2814aa51fcb981048de5c00481af53aee568ed8ce209f46004a228cf54"),
    },
    # one IMU, four hand-placed sessions (data1 with its ROS 2 bag), IMU-TK's ASCII layout, and
    # IMU-TK's own results published with them (test_imu_{acc,gyro}.calib)
    "imutk_fork_sessions": {f: FileSpec(_raw(*_FORK, f"data/{f}"), s) for f, s in _FORK_SHA256.items()},
    "fastahrs_fxos8700": {
        "data_sample.csv": FileSpec(_raw(*_FASTAHRS_1, "notebooks/data_sample.csv"),
                                    "29d9fc9eca89152280d0158c969dd4a74d33f2e9e7e94e2c50747e1a4bc503ee"),
        "data_sample2.csv": FileSpec(_raw(*_FASTAHRS_2, "notebooks/data_sample2.csv"),
                                     "c6f068238e402991238935f3173a5815d77484a9ade15dc9200810a48c294428"),
    },
    "smac_adis16405": {
        "adis_16405_imu1.rda": FileSpec(_raw(*_SMAC, "data/adis_16405_imu1.rda"),
                                        "1eb09074beabd7cfc15b402cb8043b5302f6e4edfd9e4ebfbf8117436f8b9fa9"),
    },
    "ctu_ferraris": {
        "measured_angular_rates.mat": FileSpec(_raw(*_CTU, "gyro_calibration/measured_angular_rates.mat"),
                                               "0cc8bf2c28d1525f194d67ee1374749d0409896d615e28ea9c27855c6f068962"),
        "measured_accelerations.mat": FileSpec(_raw(*_CTU, "acc_calibration/measured_accelerations.mat"),
                                               "22722ffa2dadc54b89ef85063b9446e22a996e7c25cb7e44a39a5b3657646cec"),
        "measured_accelerations_50orientations.mat": FileSpec(
            _raw(*_CTU, "acc_calibration/measured_accelerations_50orientations.mat"),
            "436e34f33ea241e94eba7d8361453b6f19bc3a1baae79cb85e69baf06bf6f511"),
    },
    "snu_static3": {f"imu_good{i}.txt": FileSpec(_raw(*_SNU, f"imu_good{i}.txt"), s)
                    for i, s in enumerate(("6eb2d25e637580306cb07c821c6f807573f25c8e9c668e3cdd034936640c4ca0",
                                           "8bf71efcd5f500caf0cbc3c1de97b6041129e3594824f5d8584325b7741b7014",
                                           "b34ed1cc40003f5323568df8976b39c3813f0494e3f065a0ee988119bfe21e9e"), start=1)},
    # magnetometer sessions (the mag stage): accelerometer + magnetometer by hand, and a magnetometer
    # alone with its author's published calibration
    "mag_ck_explorer": {
        "acc_mag_log.csv": FileSpec(_raw(*_CK, "Data Examples/acc_mag_log.csv"),
                                    "5435904892cc4eb8fc17085c30ab39430af5e29546d1c209d0bf41c588da1819"),
        "acc_log.csv": FileSpec(_raw(*_CK, "Data Examples/acc_log.csv"),
                                "738f6e3c0d8766393ddaaff717240ebab6b2726f8303b74e47eb69c8d47c152f"),
        # Apache-2.0: the licence travels with the data
        "LICENSE": FileSpec(_raw(*_CK, "LICENSE"), "9f25d93756f5ce264e47c446d09108cf782e95a1f4b387468da32fd2cd579310"),
    },
    "mag_qmc5883l_suarez": {
        "noisy_raw_data.csv": FileSpec(_raw(*_QMC, "calibration data/noisy_raw_data.csv"),
                                       "703d0f329c27d2985cef49b89bcee0d1ca0b815d3c687089d1a4d33657b0a513"),
        "filtered_raw_data.csv": FileSpec(_raw(*_QMC, "calibration data/filtered_raw_data.csv"),
                                          "850ff706b65f380d68960aff905b40672bd6448073e164f35365e9a6a457dc2c"),
        "paramters_mag.csv": FileSpec(_raw(*_QMC, "optimization result data/paramters_mag.csv"),
                                      "8b36ea49a8bfd1d388027c366901d4b79df633b20a688ba94e61860b6d5e722b"),
        "LICENSE": FileSpec(_raw(*_QMC, "LICENSE"), "e5ad1edc0cf9b8a947f0cc98f9383c8ec9b7c324652e4dd5db38482d0c5b1e70"),
    },
    "px4_ulog": {
        "sample.ulg": FileSpec(_raw(*_PYULOG, "test/sample.ulg"),
                               "81952e6059bc095717e7911c010e07f85749d6b04d332a5ffc51575a3fd0a558"),
        "sample_log_small.ulg": FileSpec(_raw(*_PYULOG, "test/sample_log_small.ulg"),
                                         "68d1020f688109f027dba08d2950247cc0ae34aaefdcf37e4a7d60838f3e1aa3"),
    },
}

#: Seconds before a download attempt gives up.
TIMEOUT_S = 60.0
_CHUNK = 1 << 16



def spec(dataset: str, filename: str) -> FileSpec:
    """The :class:`FileSpec` of one file; :class:`DatasetError` if unknown."""
    try:
        return DATASETS[dataset][filename]
    except KeyError:
        known = ", ".join(f"{d}/{f}" for d, files in DATASETS.items() for f in files)
        raise DatasetError(f"unknown measured file {dataset}/{filename}; known: {known}") from None


def fetch_file(dataset: str, filename: str, data_dir=None, resources_dir="resources", *,
               url: str | None = None, sha256: str | None = None, timeout: float = TIMEOUT_S) -> Path:
    """Local path of one measured file, from the shared copy or a verified download.

    Parameters
    ----------
    dataset, filename : str
        Keys of :data:`DATASETS` (e.g. ``'imu_tk_xsens'``, ``'xsens_acc.mat'``).
    data_dir : str or Path, optional
        Folder holding the shared copy (``<data_dir>/<dataset>/<filename>``); None or a
        missing folder means "no shared copy".
    resources_dir : str or Path
        Where downloads go (``<resources_dir>/<dataset>/<filename>``).
    url, sha256 : str, optional
        Override the table (tests use a ``file://`` URL and a known checksum).
    timeout : float
        Seconds for the download.

    Returns
    -------
    Path
        An existing file whose sha256 matches.

    Raises
    ------
    DatasetError
        Shared copy or earlier download with the wrong checksum, download failure (no
        network, HTTP error) or a downloaded file with the wrong checksum.
    """
    s = spec(dataset, filename) if url is None or sha256 is None else None
    url = url if url is not None else s.url
    want = (sha256 if sha256 is not None else s.sha256).lower()

    if data_dir is not None:
        shared = Path(data_dir) / dataset / filename
        if shared.is_file():
            got = sha256_file(shared)
            if got != want:
                raise DatasetError(f"{shared}: sha256 {got[:12]}… does not match the expected {want[:12]}… "
                                   "(damaged or different shared copy)")
            return shared

    local = Path(resources_dir) / dataset / filename
    if local.is_file():
        got = sha256_file(local)
        if got == want:
            return local
        raise DatasetError(f"{local}: sha256 {got[:12]}… does not match the expected {want[:12]}…; "
                           "delete it to download again")
    return _download(url, local, want, timeout,
                     shared_hint=None if data_dir is None else Path(data_dir) / dataset / filename)


def _download(url: str, dest: Path, want: str, timeout: float, shared_hint: Path | None) -> Path:
    h = hashlib.sha256()
    with atomic_output(dest, suffix=".part") as tmp:
        with open(tmp, "wb") as out:
            try:
                with urllib.request.urlopen(url, timeout=timeout) as resp:  # noqa: S310 (pinned URLs)
                    for block in iter(lambda: resp.read(_CHUNK), b""):
                        h.update(block)
                        out.write(block)
            except (OSError, ValueError, http.client.HTTPException) as e:  # URLError is an OSError
                reason = getattr(e, "reason", None) or e
                where = f"no shared copy at {shared_hint} and " if shared_hint is not None else ""
                fix = (f"; copy the dataset folder into {shared_hint.parent} (see shared/data/README.md) or run with "
                       "network access") if shared_hint is not None else "; run with network access"
                raise DatasetError(f"{where}download of {url} failed ({' '.join(str(reason).split())}){fix}") from None
            out.flush()
            os.fsync(out.fileno())
        got = h.hexdigest()
        if got != want:  # raised inside the block: the download is deleted, never renamed into place
            raise DatasetError(f"download of {url}: sha256 {got[:12]}… does not match the expected {want[:12]}… "
                               "(file changed upstream or corrupted in transit)")
    return dest


def fetch_dataset(dataset: str, data_dir=None, resources_dir="resources", files=None) -> dict[str, Path]:
    """:func:`fetch_file` for several files of one dataset (all of them by default)."""
    names = list(DATASETS[dataset]) if files is None else list(files)
    return {f: fetch_file(dataset, f, data_dir, resources_dir) for f in names}


__all__ = ["DATASETS", "DatasetError", "FileSpec", "fetch_dataset", "fetch_file", "spec"]
