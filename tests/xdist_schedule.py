"""The suite's pytest-xdist scheduler (tests/conftest.py): ``--dist loadfile``, a worker
given its next module only at the last test of the one it runs, and a worker that crashes
(a segfault in a C extension, an ``os.abort``) failing its test instead of hanging the run.

Kept apart from conftest.py, importing only xdist, so that tests/test_xdist_schedule.py can
run it in a small pytest session of its own.
"""

from xdist.scheduler import LoadFileScheduling


class OneModuleAhead(LoadFileScheduling):
    """``--dist loadfile``, with two changes.

    A worker gets its next module only at the last test of the one it runs (xdist gives the
    next one at the last two: the worker of the real-SLURM module, whose last tests wait
    minutes, then kept two modules that need the CI run queued while the other workers were
    idle).  The last test itself has to wait for the next module: a worker runs a test only
    once it knows the one after it.

    A crashed worker's unfinished module goes back on the queue without its finished
    modules and without the test it crashed on.  xdist 3.8's ``remove_node`` puts back
    every module the worker ever had; a replacement worker handed a finished module gets
    an empty run command, and the session waits for it forever (pytest-xdist issues 1313
    and 1323, fixed there in PRs 1324 and 1363): the whole suite hung after a reader-fuzz
    example crashed scipy's MATLAB reader.  The crashed test is already reported failed
    (``DSession.handle_crashitem``); running it again would crash the replacement too
    (pytest-xdist PR 1371).
    """

    def _reschedule(self, node):
        if node.shutting_down:
            return
        if not self.workqueue:
            node.shutdown()
            return
        # until the worker knows a test after the one it runs next; a module of one test
        # (or a replacement worker's first module) takes the next module with it
        while self.workqueue and self._pending_of(self.assigned_work[node]) <= 1:
            self._assign_work_unit(node)

    def remove_node(self, node):
        workload = self.assigned_work.pop(node)
        unfinished = [(scope, nodeid) for scope, unit in workload.items() for nodeid, done in unit.items()
                      if not done]
        if not unfinished:
            return None
        scope, crashitem = unfinished[0]  # the worker runs its tests in the order they were sent
        workload[scope][crashitem] = True
        for scope, unit in workload.items():
            if not all(unit.values()):
                self.workqueue[scope] = unit
        for other in self.assigned_work:
            self._reschedule(other)
        return crashitem
