"""LinuxCNC's single block as the adapter gives it: when a step stands done (used by
lcnc_agent.py inside LinuxCNC; no LinuxCNC module needed, so that it is tested without one).

LinuxCNC 2.9's step (`linuxcnc.command().auto(linuxcnc.AUTO_STEP)`, emctaskmain.cc
EMC_TASK_PLAN_STEP): from idle it starts the program paused (a run, then emcTrajPause); after
that each step runs one line's commands (`stepping`, STEPPING_CHECK). AXIS's single block is
this same command.
"""

# LinuxCNC's status values (its Python module's INTERP_IDLE, EXEC_WAITING_FOR_DELAY)
INTERP_IDLE = 1
EXEC_WAITING_FOR_DELAY = 8


class Stepper:
    """LinuxCNC's single block: its step (`AUTO_STEP`; emctaskmain.cc `stepping`). Stepping, the
    task's executor runs the commands of one line and stops as it takes up the first command of
    the next (STEPPING_CHECK: `currentLine` moved on from the line it stepped); motion runs that
    line's moves. The task shows no state for "step done": its status stays paused with an
    executor waiting (for IO, motion and IO) as in the middle of a line. A step stands done once
    the task's current line moved on from the line it stood at when the step was given (or the
    program ended), motion's queue is empty and the axes are in position, the executor is not in
    a dwell, for `settle` servo cycles in a row (a spindle command inside a canned cycle's line
    waits for motion with an empty queue for a task cycle; motion's outputs follow the task's
    status by a servo cycle)."""

    def __init__(self, settle=3):
        self.stepping = False
        self.line = None  # the task's current line when the running step was given; None: none runs
        self.since = None  # first servo cycle the step looked done
        self.settle = settle
        self.held = False  # the last step done, no step given since

    def step(self, line):
        self.stepping = True
        self.line = line
        self.since = None
        self.held = False

    def stop(self):
        self.stepping = False
        self.line = None
        self.held = False

    def done(self, st, cycle):
        """Whether the program stands held after a step: `st` LinuxCNC's status (polled)."""
        if self.line is None:
            return self.held
        moved_on = st.current_line != self.line or st.interp_state == INTERP_IDLE
        ready = (moved_on and st.queue == 0 and bool(st.inpos)
                 and st.exec_state != EXEC_WAITING_FOR_DELAY)
        if not ready:
            self.since = None
            return False
        if self.since is None:
            self.since = cycle
        if cycle - self.since >= self.settle:
            self.line = None
            self.held = True
        return self.held
