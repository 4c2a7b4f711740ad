"""The workflow's fix to Snakemake's scheduler wake-ups (workflow/rules/scheduler.smk): one
pending timer instead of one more per scheduling pass."""

import inspect
import threading
import time
from types import SimpleNamespace

import snakemake.scheduling.job_scheduler as job_scheduler

from tests.snakemake_plan import REPO, planned_jobs


def test_the_pinned_snakemake_still_arms_a_timer_on_every_pass():
    """What the fix works around, read from Snakemake's own source: a new Timer per call.
    When an upgrade changes it, this fails and the fix is looked at again."""
    source = inspect.getsource(job_scheduler)
    method = source[source.index("def _schedule_reevalutation"):]
    method = method[:method.index("\n    def ", 1)]
    assert "threading.Timer(" in method and "_open_jobs.release()" in method, method
    assert "self._schedule_reevalutation(self.job_rate_limiter.timespan)" in source


def test_a_workflow_parse_installs_the_fix(tmp_path):
    planned_jobs(tmp_path, ["burkhard2024_fig1a"], [REPO / "config" / "ci.yaml"])
    assert job_scheduler.JobScheduler._schedule_reevalutation.__name__ == "_one_pending_reevaluation"


def test_many_passes_arm_one_timer_and_each_wakeup_rearms(tmp_path):
    planned_jobs(tmp_path, ["burkhard2024_fig1a"], [REPO / "config" / "ci.yaml"])
    scheduler = SimpleNamespace(_open_jobs=threading.Semaphore(0))
    reevaluate = job_scheduler.JobScheduler._schedule_reevalutation
    for _ in range(50):  # 50 passes within the timespan: the released method armed 50 timers
        reevaluate(scheduler, 0.05)
    assert scheduler._open_jobs.acquire(timeout=2.0)  # the one wake-up
    time.sleep(0.2)
    assert not scheduler._open_jobs.acquire(blocking=False), "more than one wake-up for 50 passes"
    reevaluate(scheduler, 0.05)  # the pass the wake-up started arms the next one
    assert scheduler._open_jobs.acquire(timeout=2.0)
