"""Command line: ``accelcal calibrate``, ``accelcal apply``, ``accelcal export``, ``accelcal discrepancy``,
``accelcal noise``, ``accelcal mag``.

One module per subcommand (``add_parser`` and its handler), the shared options in
:mod:`.common`.

Nothing numerical is imported at module level: ``accelcal --help`` must start at once.
Every failure the user can fix is one ``accelcal: error:`` line on stderr naming the
cause and the option that fixes it, exit status 2, and no output file; warnings about a
result that was written are ``warning:`` lines (a clean fit prints none).  Exit status 3
is kept for ``--strict`` (``calibrate``, ``export``): the calibration's fit is untrustworthy;
an internal error (a bug) is 4.
"""

from __future__ import annotations

import argparse
import os
import sys

from .. import __version__
from ..errors import AccelcalError
from ..formats.registry import formats_help
from . import apply, calibrate, discrepancy, export, mag, noise
from .common import MODEL_HELP, STANDARD_GRAVITY, _methods_help, fail

#: The subcommands, in the order the help lists them.
SUBCOMMANDS = (calibrate, apply, export, discrepancy, noise, mag)


#: One BLAS thread unless the user chose: the command's matrices are small, and threads of a
#: multi-threaded BLAS spin for each other (Xsens acc + gyro: 0.85 s of CPU with two, 0.62 s
#: with one, the same wall time).  Read when numpy loads, i.e. after this (as the workflow's Snakefile).
BLAS_THREADS = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def main(argv: list[str] | None = None) -> int:
    for var, value in BLAS_THREADS.items():
        os.environ.setdefault(var, value)
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except AccelcalError as exc:
        return fail(str(exc))
    except OSError as exc:
        return fail(f"{exc.strerror or exc}: {exc.filename}" if getattr(exc, "filename", None) else str(exc))
    except KeyboardInterrupt:
        return fail("interrupted", code=130)
    except Exception as exc:  # never a traceback for the user; ACCELCAL_DEBUG=1 shows it
        if os.environ.get("ACCELCAL_DEBUG"):
            raise
        return fail(f"internal error ({type(exc).__name__}: {exc}); rerun with ACCELCAL_DEBUG=1 and report it", code=4)


def _parser() -> argparse.ArgumentParser:
    epilog = MODEL_HELP.format(methods=_methods_help(), formats=formats_help())
    p = argparse.ArgumentParser(prog="accelcal", description="IMU calibration: accelerometer, gyroscope, magnetometer and noise.",
                                formatter_class=argparse.RawDescriptionHelpFormatter, epilog=epilog)
    p.add_argument("--version", action="version", version=f"accelcal {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    for command in SUBCOMMANDS:
        command.add_parser(sub, epilog)
    return p


__all__ = ["STANDARD_GRAVITY", "main"]


if __name__ == "__main__":
    sys.exit(main())
