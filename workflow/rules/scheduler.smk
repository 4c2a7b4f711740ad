# One pending scheduler wake-up at a time (a fix to Snakemake's local scheduler, not a rule).
#
# Snakemake 9.27.1 (the lock's pin) arms a new threading.Timer after every scheduling pass
# while jobs wait (JobScheduler._schedule_reevalutation, job_scheduler.py lines 394-397 and
# 410-413; it lets --max-jobs-per-timespan, default 100/1s, start more jobs once the timespan
# is over).  Each timer's release makes one more pass, which arms one more timer, and every
# job that finishes adds a pass of its own: the timers never merge, so after k finished jobs
# the scheduler makes about k passes a second, each of which re-reads the waiting jobs' input
# sizes and runs an event loop.  Measured in one run each (Snakemake's own CPU, its jobs'
# excluded): 160 jobs that only sleep 1 s on 2 cores, 6,403 passes and 7.2 CPU-s as released,
# 240 passes and 2.2 CPU-s with one pending timer; the CI-config workflow run on a loaded
# machine spent 53 CPU-s in Snakemake's own process.  One pending timer is all the limiter
# needs (a pass at most one timespan after the last), so the others are not armed.
#
# Applied only where the method is the one this works around (the test
# tests/test_scheduler_wakeups.py fails when the pinned Snakemake changes it, so that the
# fix is looked at again, and checks that a workflow parse installs it).
import inspect as _inspect
import threading as _threading

from snakemake.scheduling.job_scheduler import JobScheduler as _JobScheduler


def _one_pending_reevaluation(self, delay):
    """Wake the scheduler after ``delay`` seconds unless a wake-up is already pending."""
    if getattr(self, "_accelcal_wakeup_pending", False):
        return
    self._accelcal_wakeup_pending = True

    def wake():
        self._accelcal_wakeup_pending = False  # before the release: the pass it starts re-arms
        self._open_jobs.release()

    _threading.Timer(delay, wake).start()


def _arms_a_timer_per_pass(method) -> bool:
    """Whether ``method`` is the released one (not this file's from an earlier parse), read
    from its source; False where the source is not installed (nothing is replaced then)."""
    if method is None or method.__name__ != "_schedule_reevalutation":
        return False
    try:
        return "threading.Timer(" in _inspect.getsource(method)
    except (OSError, TypeError):
        return False


if _arms_a_timer_per_pass(getattr(_JobScheduler, "_schedule_reevalutation", None)):
    _JobScheduler._schedule_reevalutation = _one_pending_reevaluation
