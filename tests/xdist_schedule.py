"""The suite's pytest-xdist scheduler (tests/conftest.py): ``--dist loadfile``, a worker
given its next module only at the last test of the one it runs, and a worker that crashes
(a segfault in a C extension, an ``os.abort``) failing its test instead of hanging the run.

Kept apart from conftest.py, importing only xdist, so that tests/test_xdist_schedule.py can
run it in a small pytest session of its own.
"""

from xdist.scheduler import LoadFileScheduling


class OneModuleAhead(LoadFileScheduling):
    """``--dist loadfile``, with three changes.

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

    The modules that read a run made by another module (``after``, longest first: the CI
    workflow run, made by the first test of ``gate``) go to the next free worker, ahead of
    the queue, as soon as a test of ``gate`` has ended, and last before that (dispatched
    early they would hold a worker idle while the run is made).  Handed out in queue
    order, the longest of them (the forced reruns of the CI run's jobs) started after the
    light modules queued before it and ran alone at the end of the suite.
    """

    def __init__(self, config, log=None, after=(), gate=None):
        super().__init__(config, log)
        self.after, self.gate, self.gate_passed = tuple(after), gate, False

    @staticmethod
    def module(scope):
        return scope.rsplit("/", 1)[-1]

    def next_scope(self):
        """The module a worker gets next (see the class's docstring)."""
        waiting = [s for s in self.workqueue if self.module(s) in self.after]
        others = [s for s in self.workqueue if self.module(s) not in self.after]
        if waiting and (self.gate_passed or not others):
            return min(waiting, key=lambda s: self.after.index(self.module(s)))
        return others[0]

    def mark_test_complete(self, node, item_index, duration=0):
        if self.module(self._split_scope(self.registered_collections[node][item_index])) == self.gate:
            self.gate_passed = True
        super().mark_test_complete(node, item_index, duration)

    def _assign_work_unit(self, node):
        scope = self.next_scope()
        work_unit = self.workqueue.pop(scope)
        self.assigned_work.setdefault(node, {})[scope] = work_unit
        collection = self.registered_collections[node]
        node.send_runtest_some([collection.index(nodeid) for nodeid, done in work_unit.items() if not done])

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
