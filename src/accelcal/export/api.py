"""What ``accelcal export`` does with a consumer of the registry: check what it needs (a
gyroscope, a noise report), that the calibration is plausible (:mod:`.plausibility`), write,
and refuse a lossy export only when asked for exactness; :func:`write_files` puts the files
in place whole or not at all."""


from __future__ import annotations

from contextlib import ExitStack
from pathlib import Path

from ..atomic import atomic_output
from .base import Export, ExportError, ExportInputs, LeftOut, require_gyro, require_noise
from .plausibility import check_plausible, trust_problems
from .registry import CONSUMERS, add_section, consumer_named, consumers_help


def export(consumer: str, inputs: ExportInputs, *, exact: bool = False, plausible: bool = True) -> Export:
    """The consumer's files for ``inputs``.

    Raises
    ------
    ExportError
        Something the consumer needs is missing, the calibration is implausible, or
        ``exact`` and the consumer's model cannot hold a term (one line each).
    """

    c = consumer_named(consumer)
    cal = inputs.calibration
    if "gyro" in c.needs:
        require_gyro(cal, c.name, "its file holds the gyroscope's calibration")
    if "noise" in c.needs:
        require_noise(inputs, c.name)
    if plausible:
        check_plausible(cal, acc_range_g=inputs.option("acc_range_g", 16.0),
                        gyro_range_dps=inputs.option("gyro_range_dps", 2000.0))
    result = c.load_writer()(inputs)
    lost = [x for x in result.left_out if x.exact_loss]
    if exact and lost:
        raise ExportError(f"--exact: {c.name}'s model cannot hold {lost[0].term} ({lost[0].cost})"
                          + (f" and {len(lost) - 1} more" if len(lost) > 1 else "")
                          + "; export without --exact to accept the loss")
    return result


def output_paths(consumer: str, path, result: Export) -> dict[Path, str]:
    """Where each of ``result``'s files goes: ``path`` + suffix (``path`` itself for '')."""
    return {Path(f"{path}{suffix}"): text for suffix, text in result.files.items()}


def write_files(files: dict) -> None:
    """Write every file, each renamed into place only once all are written."""

    with ExitStack() as stack:
        for path, text in files.items():
            Path(stack.enter_context(atomic_output(path))).write_text(text)


__all__ = ["CONSUMERS", "Export", "ExportError", "ExportInputs", "LeftOut", "add_section", "check_plausible",
           "consumer_named", "consumers_help", "export", "output_paths", "trust_problems", "write_files"]
