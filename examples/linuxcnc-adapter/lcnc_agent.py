#!/usr/bin/python3
"""The adapter's agent inside LinuxCNC: the machine configuration's DISPLAY program (LinuxCNC
starts it once the HAL, task and motion are up, and shuts down when it exits).

It connects to the adapter's Unix socket ($LCNC_AGENT_SOCK), turns the machine on, homes it, and
then serves one request per line:

- `{"op":"run", ...}`: one program run with its operator inputs at their times (see `run`): the
  HAL sampler records every servo cycle into a file, the agent logs what LinuxCNC's task said
  (interpreter state, pause, errors) and when each input was given, in servo cycles of the
  machine's clock (`servo_clock`, an `integ` of 1 in the servo thread);
- `{"op":"quit"}`: exit (LinuxCNC shuts down).

Runs under LinuxCNC's own Python (the `linuxcnc` and `hal` modules). Standard library otherwise.
"""

import json
import os
import select
import socket
import subprocess
import sys
import time

import hal
import linuxcnc
from lcnc_step import Stepper

c = linuxcnc.command()
s = linuxcnc.stat()
e = linuxcnc.error_channel()


def log(*a):
    print("lcnc-agent:", *a, file=sys.stderr, flush=True)


class Clock:
    """The servo cycle count, read from the HAL (the same value the sampler records)."""

    def __init__(self, period_s):
        self.period_s = period_s

    def now(self):
        return int(round(hal.get_value("servo_clock.out") / self.period_s))


# The E-stop a HAL comparator gives at a servo cycle (lcnc_machine.HAL_TEMPLATE: estop_at drops
# motion.enable and the spindle command in that cycle); its message is the E-stop's own echo.
ESTOP_DISARMED = "1e12"
ESTOP_ECHO = "motion stopped by enable input"


def hal_estop():
    """Whether the machine's HAL has the E-stop comparator (a user's own HAL may not: the
    E-stop then goes through the task, ~16 ms late where its latency is not yet measured)."""
    try:
        hal.get_value("estop_at.out")
        return True
    except Exception:
        return False


def arm_estop(trip, period_s):
    """E-stop from servo cycle `trip` on: estop_at runs first in the cycle, on the clock of the
    cycle before (`trip` - 1), so its threshold lies half a period below that."""
    hal.set_p("estop_at.in0", repr((trip - 1.5) * period_s))


def errors(sink, clock):
    """LinuxCNC's operator messages since the last call, stamped."""
    while True:
        m = e.poll()
        if not m:
            return
        kind, text = m
        s.poll()
        sink.append({"cycle": clock.now(), "kind": int(kind), "text": str(text), "read_line": s.read_line,
                     "current_line": s.current_line, "motion_line": s.motion_line})


def wait(cond, timeout, what, sink=None, clock=None):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        s.poll()
        if cond():
            return
        if sink is not None:
            errors(sink, clock)
        time.sleep(0.005)
    raise RuntimeError("timeout waiting for " + what)


def machine_on(msgs, clock):
    """E-stop reset and machine on, repeated until the state shows it (2.9's separate IO
    program may take the first commands before it is ready), then home in place."""
    for _ in range(50):
        s.poll()
        if s.task_state == linuxcnc.STATE_ON:
            break
        c.state(linuxcnc.STATE_ESTOP_RESET if s.task_state == linuxcnc.STATE_ESTOP else linuxcnc.STATE_ON)
        c.wait_complete(1.0)
        time.sleep(0.1)
        errors(msgs, clock)
    else:
        raise RuntimeError("the machine does not turn on")
    s.poll()
    if not all(s.homed[i] for i in range(3)):
        c.mode(linuxcnc.MODE_MANUAL)
        c.wait_complete()
        c.teleop_enable(0)
        c.wait_complete()
        c.home(-1)
        wait(lambda: all(s.homed[i] for i in range(3)), 30, "homing")


# Blocks that bring the machine back to the dialect's power-on state between runs (modal codes
# as the reference's power-on, offsets cleared, spindle and coolant off, at machine zero). What a
# program leaves in the kept LinuxCNC and its reset/abort does not clear:
# - the overrides' enables: G74/G84 disable feed and spindle override and enable them again after
#   the cycle only when motion reported them enabled as the interpreter read the line
#   (interp_cycles.cc `convert_cycle_g74_g84`, GET_EXTERNAL_FEED_OVERRIDE_ENABLE), and an abort
#   inside the cycle or a program's M49 leaves them off: M48 turns both on;
# - a canned cycle's dwell P: the interpreter keeps the last cycle's P (`settings->cycle_p`) for the
#   next cycle without P, across programs (its init() does not clear it): a G84 after a G88 P0.3
#   dwelt 0.3 s at the bottom. A cycle with P0 that moves nothing (at machine zero, R = Z = 0) sets
#   it back to the power-on 0.
POWER_ON_MDI = [
    "G92.1",
    "G10 L2 P1 X0 Y0 Z0",
    "G17 G21 G40 G49 G54 G80 G90 G94 G99 G8 {path_mode} M5 M9",
    "M48",
    "G53 G0 X0 Y0 Z0",
    "G90 G98 G82 X0 Y0 Z0 R0 P0 F1",
    "G80 G99",
    "F0 S0",
]


def prepare(msgs, clock, path_mode="G64"):
    """Power-on state: aborted, machine on and homed, power-on modes, overrides 100 %, at machine
    zero, spindle stopped with its angle at 0 (the sim spindle's position reset)."""
    c.abort()
    c.wait_complete(2.0)
    hal.set_p("stall.sel", "0")
    if hal_estop():
        # motion's enable back on before the machine is (an E-stop of the last run left it off)
        hal.set_p("estop_at.in0", ESTOP_DISARMED)
        time.sleep(0.01)
    machine_on(msgs, clock)
    c.mode(linuxcnc.MODE_MDI)
    c.wait_complete()
    c.reset_interpreter()
    c.wait_complete()
    for line in POWER_ON_MDI:
        line = line.format(path_mode=path_mode)
        c.mdi(line)
        c.wait_complete(5.0)
        wait(lambda: s.interp_state == linuxcnc.INTERP_IDLE, 30, "MDI " + line, msgs, clock)
    c.feedrate(1.0)
    c.spindleoverride(1.0, 0)
    s.poll()
    if not (s.feed_override_enabled and s.spindle[0]["override_enabled"]):
        raise RuntimeError("the overrides are still disabled after M48")
    c.set_optional_stop(0)
    c.set_block_delete(0)
    wait(lambda: s.inpos and abs(hal.get_value("spindle-speed-limited")) < 1e-9, 30, "machine at rest")
    zero_spindle()
    errors(msgs, clock)


def zero_spindle():
    """Turns the stopped sim spindle to the nearest whole revolution (its index, the reference's
    angle 0 at power-on), within 1e-5 revolution: a HAL signal with a writer cannot be set, so the
    spindle is driven through the stall switch's other input at a speed that covers 90 % of the
    way in about 0.1 s, a few times over."""
    for _ in range(12):
        pos = hal.get_value("spindle-pos")
        d = round(pos) - pos
        if abs(d) < 1e-5:
            break
        # rpm for 0.9 * d revolutions in 0.1 s (velocity-cmd is in rpm, scale 1/60)
        hal.set_p("stall.in1", str(0.9 * d / 0.1 * 60.0))
        hal.set_p("stall.sel", "1")
        time.sleep(0.1)
        hal.set_p("stall.sel", "0")
        hal.set_p("stall.in1", "0")
        time.sleep(0.005)
    hal.set_p("stall.in1", "0")
    hal.set_p("stall.sel", "0")


SOCK = None
_last_check = [0.0]


def adapter_gone():
    """The adapter closed its end (it was stopped): LinuxCNC must not be left running."""
    now = time.monotonic()
    if SOCK is None or now - _last_check[0] < 0.1:
        return False
    _last_check[0] = now
    r, _, _ = select.select([SOCK], [], [], 0)
    if not r:
        return False
    try:
        head = SOCK.recv(16, socket.MSG_PEEK)
        return head == b"" or head.startswith(b'{"op":"quit"')
    except OSError:
        return True


def held():
    """The program stands held (the SPL lamp): paused by feed hold or M0/M1 (the interpreter
    paused, as halui's program.is-paused), or a single-block step done (task paused with nothing
    left in motion's queue)."""
    if s.interp_state == linuxcnc.INTERP_PAUSED:
        return True
    return bool(s.task_paused) and s.queue == 0 and bool(s.inpos)


def clamp(x, lo, hi):
    return max(lo, min(hi, x))


class Commanders:
    """LinuxCNC's Python interface waits for the task to take each command (it polls every 10 ms,
    ~20 ms in all), so commands are sent from child processes, in turn, while the agent keeps
    watching the servo clock and the task's status."""

    def __init__(self, n=3):
        self.pipes = []
        for _ in range(n):
            r, w = os.pipe()
            if os.fork() == 0:
                os.close(w)
                cc = linuxcnc.command()
                with os.fdopen(r) as f:
                    for line in f:
                        op = json.loads(line)
                        getattr(cc, op[0])(*op[1:])
                os._exit(0)
            os.close(r)
            self.pipes.append(os.fdopen(w, "w"))
        self.k = 0

    def send(self, cmd):
        f = self.pipes[self.k]
        self.k = (self.k + 1) % len(self.pipes)
        f.write(json.dumps(list(cmd)) + "\n")
        f.flush()


COMMANDERS = None


class Run:
    """One program run. Request keys: `program` (path), `out` (recording path), `inputs`
    ([{"t_us", "input", "lead_us"}], by time), `time_limit_us`, `auto_cycle_start`, `t0_lead`
    (servo cycles from the run command to the program's first output, as seen in an earlier run;
    used until this run shows its own), `cfg` (period_us, override limits), `hold_ms` (a program
    held with no input left to release it is stopped after this long)."""

    def __init__(self, req, clock):
        self.req = req
        self.clock = clock
        self.cfg = req["cfg"]
        self.period_us = self.cfg["period_us"]
        self.msgs = []
        self.states = []
        self.given = []
        self.single_block = False
        self.stepper = Stepper()
        self.before = None  # the outputs before the start
        self.restep = False  # single block: line 1 changes an output, not seen yet after the start
        self.restepped = None
        self.start_paused = False  # single block: the start's pause before line 1, not left yet
        self.commanders = COMMANDERS
        # the E-stop given through HAL (estop_at): the servo cycle it is armed for, once armed
        self.estop_trip = self.estop_due = self.estop_input = None
        self.hal_estop = hal_estop()

    def snapshot(self):
        """The outputs whose first change marks the program's start (t = 0)."""
        g = hal.get_value
        return (
            round(g("Xpos"), 9), round(g("Ypos"), 9), round(g("Zpos"), 9), g("spindle.0.on"),
            g("spindle.0.speed-out"), g("motion.program-line"), g("motion.motion-type"),
            g("iocontrol.0.coolant-flood"), g("iocontrol.0.coolant-mist"),
        )

    def give(self, inp, cycle_due, direct=False):
        """Applies one input through LinuxCNC's Python interface (as a GUI's buttons do) and
        records when LinuxCNC's task took it (its status echoes the command's serial number);
        returns None, or why it cannot be given. `direct`: before the start, sent and waited for
        here."""
        name = inp["name"]
        before = self.clock.now()
        s.poll()
        cmd = None
        if name == "feed_hold":
            cmd = ("auto", linuxcnc.AUTO_PAUSE)
        elif name == "cycle_start":
            if self.single_block and self.stepper.stepping and not s.interp_state == linuxcnc.INTERP_PAUSED:
                # the next line, once the line before stands done (a cycle start while it runs is
                # not a second step: LinuxCNC would run on through the next line)
                if self.held():
                    cmd = ("auto", linuxcnc.AUTO_STEP)
                    self.stepper.step(s.current_line)
            elif self.held() or s.task_paused:
                if self.single_block:
                    cmd = ("auto", linuxcnc.AUTO_STEP)
                    self.stepper.step(s.current_line)
                else:
                    cmd = ("auto", linuxcnc.AUTO_RESUME)
                    self.stepper.stop()
        elif name == "reset":
            cmd = ("abort",)
        elif name == "single_block":
            self.single_block = bool(inp["on"])
            running = s.interp_state in (linuxcnc.INTERP_READING, linuxcnc.INTERP_WAITING)
            if self.single_block and running and not self.stepper.stepping:
                # LinuxCNC's step while it runs: it stops once the current line is done
                cmd = ("auto", linuxcnc.AUTO_STEP)
                self.stepper.step(s.current_line)
            elif not self.single_block and running and self.stepper.stepping and not self.held():
                # off while a line runs: the program runs on (a resume ends LinuxCNC's stepping)
                cmd = ("auto", linuxcnc.AUTO_RESUME)
                self.stepper.stop()
        elif name == "optional_stop":
            cmd = ("set_optional_stop", 1 if inp["on"] else 0)
        elif name == "emergency_stop":
            cmd = ("state", linuxcnc.STATE_ESTOP if inp["on"] else linuxcnc.STATE_ESTOP_RESET)
        elif name == "feed_override":
            cmd = ("feedrate", clamp(inp["percent"] / 100.0, 0.0, self.cfg["feed_override_max"]))
        elif name == "spindle_override":
            f = clamp(inp["percent"] / 100.0, self.cfg["spindle_override_min"], self.cfg["spindle_override_max"])
            cmd = ("spindleoverride", f, 0)
        elif name == "spindle_stall":
            hal.set_p("stall.sel", "1" if inp["on"] else "0")
        else:
            return f"LinuxCNC has no counterpart of the `{name}` input"
        g = {"cycle": before, "sent": before, "due": cycle_due, "input": inp}
        if name == "emergency_stop" and inp["on"] and self.estop_trip is not None:
            # HAL stopped motion and the spindle at the armed cycle; the task is told as well (its
            # E-stop state, the alarm), ~16 ms later
            g["cycle"] = g["sent"] = self.estop_trip
            g["hal"] = True
            self.commanders.send(cmd)
            self.given.append(g)
            return None
        if cmd is not None:
            if direct:
                # before the start: on time whenever the task takes it (its latency is still
                # measured, for the same input during the run)
                getattr(c, cmd[0])(*cmd[1:])
                g["cycle"] = g["due"] = self.clock.now()
            else:
                g["echo"] = s.echo_serial_number
                g["estop"] = name == "emergency_stop" and inp["on"]
                g["cycle"] = None
                self.commanders.send(cmd)
        self.given.append(g)
        return None

    def acks(self):
        """Stamps the inputs LinuxCNC's task has now taken."""
        for g in self.given:
            if g["cycle"] is None:
                name = g["input"]["name"]
                # taken: the task echoes the command's serial, or its state shows the command (an
                # abort's echo comes only once it is done, ~150 ms after motion stopped)
                took = s.echo_serial_number != g["echo"] or (
                    (g["estop"] and s.task_state == linuxcnc.STATE_ESTOP)
                    or (name == "reset" and s.interp_state == linuxcnc.INTERP_IDLE)
                    or (name == "feed_hold" and s.interp_state == linuxcnc.INTERP_PAUSED)
                )
                if took:
                    g["cycle"] = self.clock.now()

    def state(self):
        s.poll()
        self.acks()
        # "paused" as halui's program.is-paused: the interpreter is paused (feed hold, a
        # single-block step done, M0/M1)
        return (s.interp_state, self.held(), s.task_state, s.exec_state, bool(s.paused), bool(s.task_paused), s.queue)

    def held(self):
        """The program stands held (the SPL lamp): paused by feed hold or M0/M1 (the interpreter
        paused, as halui's program.is-paused), or, single-stepping, the step's line done."""
        if self.start_paused:
            # the single-block start's step from idle pauses the program before line 1 (the
            # reference's single block has no such stop): not held
            if s.interp_state == linuxcnc.INTERP_PAUSED:
                return False
            self.start_paused = False
        if self.stepper.stepping and s.interp_state != linuxcnc.INTERP_PAUSED:
            done = self.stepper.done(s, self.clock.now())
            if done and self.restep and self.snapshot() == self.before:
                # the start's step ran no line: LinuxCNC's executor took up a command left from
                # before the run (its status shows a line further on, waiting for motion and IO)
                # and stood there, in some runs of a scenario, not in others; line 1, which
                # changes an output, did not run: one more step runs it
                self.restep = False
                self.restepped = self.clock.now()
                self.stepper.step(s.current_line)
                self.commanders.send(("auto", linuxcnc.AUTO_STEP))
                return False
            if done:
                self.restep = False
            return done
        return held()

    def run(self):
        req, clock = self.req, self.clock
        per_ms = 1000.0 / self.period_us
        c.mode(linuxcnc.MODE_AUTO)
        c.wait_complete()
        c.program_open(req["program"])
        c.wait_complete()
        out = open(req["out"], "w")
        sampler = subprocess.Popen(["halsampler", "-t"], stdout=out)
        time.sleep(0.05)
        pending = list(req["inputs"])
        # Inputs at 0 that set a switch act before the start (the reference applies them before
        # its first step); the others wait for the program's first output.
        early = {"feed_override", "spindle_override", "single_block", "optional_stop", "spindle_stall"}
        hal.set_p("sampler.0.enable", "1")
        time.sleep(0.01)
        before = self.before = self.snapshot()
        for p in [p for p in pending if p["t_us"] == 0 and p["input"]["name"] in early]:
            pending.remove(p)
            why = self.give(p["input"], clock.now(), direct=True)
            if why:
                return self.finish(out, sampler, {"not_applicable": why})
        if self.single_block:
            # LinuxCNC's first step from idle starts the program paused (emctaskmain.cc: a run,
            # then emcTrajPause: no output yet); the second runs line 1 (the reference's single
            # block runs the first block at once), sent from a commander as the run command
            # below. In some runs of a scenario, not in others, the second step ran no line (the
            # task took up a stale command and stood): see `held`.
            c.auto(linuxcnc.AUTO_STEP)
            c.wait_complete(1.0)
            time.sleep(0.02)
            s.poll()
            self.stepper.step(s.current_line)
            self.restep = bool(req.get("first_line_acts"))
            self.start_paused = True
            c_run = clock.now()
            self.commanders.send(("auto", linuxcnc.AUTO_STEP))
        else:
            # The run command goes out from a commander: the Python interface returns only once
            # the task took it (~20 ms), and the program's first output, time 0 of the inputs'
            # times, is seen from here by then (a time 0 taken 17 ms late gave every input 17 ms
            # late: g84/overrides_and_feed_hold held 0.17 mm deep)
            c_run = clock.now()
            self.commanders.send(("auto", linuxcnc.AUTO_RUN, 0))
        wall0 = time.monotonic()
        wall_limit = req["time_limit_us"] / 1e6 * 3 + 30
        t0 = None
        t0_guess = c_run + int(req.get("t0_lead", 2))
        last = None
        looks = 0
        end = None
        limit_cycles = int(req["time_limit_us"] // self.period_us)
        budget_cycles = int(req.get("budget_us", req["time_limit_us"]) // self.period_us) + 1000 * int(per_ms)
        started = False
        held_since = None
        reset_at = None
        last_pos, moved_at = None, c_run
        while end is None:
            looks += 1
            now = clock.now()
            pos = (hal.get_value("Xpos"), hal.get_value("Ypos"), hal.get_value("Zpos"))
            if pos != last_pos:
                last_pos, moved_at = pos, now
            st = self.state()
            if st != last:
                self.states.append({"cycle": now, "interp": st[0], "paused": st[1], "task": st[2], "exec": st[3],
                                    "motion_paused": st[4], "task_paused": st[5], "queue": st[6],
                                    "line": s.current_line, "motion_line": s.motion_line,
                                    "step": bool(st[1] and self.stepper.held)})
                last = st
            errors(self.msgs, clock)
            if t0 is None and self.snapshot() != before:
                # an output changed before the first look (the step given from here): at the
                # run command + the lead an earlier run showed
                t0 = now if looks > 1 else min(now, t0_guess)
            base = t0 if t0 is not None else t0_guess
            self.arm_estop(pending, base, now)
            while pending:
                p = pending[0]
                due = base + int(round(p["t_us"] / self.period_us))
                lead = int(round(p.get("lead_us", 0) / self.period_us))
                if self.estop_trip is not None and p is self.estop_input:
                    # given through HAL at its cycle: no lead, given once HAL has acted
                    if not hal.get_value("estop_at.out"):
                        break
                elif now < due - lead:
                    break
                pending.pop(0)
                why = self.give(p["input"], due)
                if why:
                    return self.finish(out, sampler, {"not_applicable": why})
                if p["input"]["name"] == "reset":
                    reset_at = now
            running = st[0] != linuxcnc.INTERP_IDLE
            hal_stopped = any(g.get("hal") for g in self.given)
            # started: seen running, or an output changed, or still idle 200 ms after the run
            # command (an error before the first block ends it at once)
            started = started or running or t0 is not None or now - c_run > 200 * per_ms
            reset_taken = next((g["cycle"] for g in self.given if g["input"]["name"] == "reset" and g["cycle"]), None)
            if reset_at is not None and ((reset_taken and now - reset_taken > 20 * per_ms) or now - reset_at > 1000 * per_ms):
                end = {"reason": "reset", "cycle": reset_taken or reset_at}
            elif t0 is not None and now - t0 >= limit_cycles:
                c.abort()
                end = {"reason": "time_limit", "cycle": t0 + limit_cycles, "limit_cycles": limit_cycles}
            elif now - c_run >= budget_cycles:
                c.abort()
                end = {"reason": "over_budget", "cycle": now}
            elif st[2] == linuxcnc.STATE_ESTOP or (hal_stopped and now - self.estop_trip > 1000 * per_ms):
                end = {"reason": "alarm", "cycle": now, "estop": True}
            elif hal_stopped:
                # motion stopped by HAL's E-stop: the task aborts the program (its interpreter
                # idle, not a program end) and takes the E-stop state once its command arrives
                pass
            elif started and not running and reset_at is None:
                end = self.settle({"reason": "program_end", "cycle": now})
            elif st[1]:
                if req.get("auto_cycle_start"):
                    if not self.given or self.given[-1]["cycle"] is not None:
                        self.give({"name": "cycle_start"}, now)
                        self.given[-1]["auto"] = True
                elif not pending:
                    # held for hold_ms with the axes standing: a pause LinuxCNC defers (inside
                    # a synchronised move) has taken effect by then
                    held_since = max(held_since if held_since is not None else now, moved_at)
                    if now - held_since > req.get("hold_ms", 500) * per_ms:
                        end = {"reason": "stopped", "cycle": now}
                else:
                    held_since = None
            else:
                held_since = None
            if t0 is None and now - c_run >= limit_cycles:
                end = {"reason": "time_limit", "cycle": now}
            if adapter_gone():
                c.abort()
                raise SystemExit("the adapter is gone")
            if time.monotonic() - wall0 > wall_limit:
                end = {"reason": "time_limit", "cycle": now, "wall": True}
            time.sleep(0.0003)
        if end["reason"] in ("stopped", "time_limit", "alarm", "over_budget"):
            c.abort()
        return self.finish(out, sampler, {"end": end, "t0": t0, "c_run": c_run, "restepped": self.restepped})

    def arm_estop(self, pending, base, now):
        """Arms HAL's E-stop for the next E-stop input at its servo cycle (at once when that has
        passed: two cycles on, the one running may be past estop_at already); again when time 0,
        which the cycle counts from, is found after a guess. Not once it has acted."""
        if not self.hal_estop or (self.estop_trip is not None and hal.get_value("estop_at.out")):
            return
        p = next((p for p in pending if p["input"]["name"] == "emergency_stop" and p["input"].get("on")), None)
        if p is None:
            return
        due = base + int(round(p["t_us"] / self.period_us))
        if self.estop_trip is None or due != self.estop_due:
            self.estop_trip, self.estop_due, self.estop_input = max(due, now + 2), due, p
            arm_estop(self.estop_trip, self.clock.period_s)

    def settle(self, end):
        """After the program's end: record until the spindle stands and the axes are in position
        (the reference's end comes once the spindle has stopped), at most 30 s."""
        t0 = time.monotonic()
        while time.monotonic() - t0 < 30:
            s.poll()
            errors(self.msgs, self.clock)
            if s.inpos and abs(hal.get_value("spindle-speed-limited")) < 1e-9:
                break
            time.sleep(0.002)
        end["settled"] = self.clock.now()
        return end

    def finish(self, out, sampler, result):
        time.sleep(0.03)
        hal.set_p("sampler.0.enable", "0")
        time.sleep(0.1)
        sampler.terminate()
        sampler.wait()
        out.close()
        errors(self.msgs, self.clock)
        if any(g.get("hal") for g in self.given):
            # motion's own report of the E-stop HAL gave is not an alarm of the program's
            self.msgs = [m for m in self.msgs if m["text"].strip() != ESTOP_ECHO]
        s.poll()
        self.acks()
        for g in self.given:
            if g["cycle"] is None:
                g["cycle"] = g["sent"]
                g["unacknowledged"] = True
            g.pop("echo", None)
        result["gcodes"] = list(s.gcodes)
        result.update({"ok": True, "messages": self.msgs, "states": self.states, "given": self.given})
        return result


def main():
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    sock.connect(os.environ["LCNC_AGENT_SOCK"])
    global SOCK
    SOCK = sock
    rfile = sock.makefile("r")

    def answer(obj):
        sock.sendall((json.dumps(obj) + "\n").encode())

    try:
        h = hal.component("ncconform_agent")
        h.ready()
        wait(lambda: True, 10, "status")
        msgs = []
        period_s = 0.001
        clock = Clock(period_s)
        machine_on(msgs, clock)
    except Exception as ex:  # the adapter reports it with LinuxCNC's log
        answer({"ok": False, "error": f"{type(ex).__name__}: {ex}"})
        return
    global COMMANDERS
    COMMANDERS = Commanders()
    answer({"ok": True, "version": getattr(linuxcnc, "version", "?")})
    for line in rfile:
        req = json.loads(line)
        if req.get("op") == "quit":
            break
        try:
            clock.period_s = req["cfg"]["period_us"] / 1e6
            msgs = []
            prepare(msgs, clock, req["cfg"].get("path_mode", "G64"))
            res = Run(req, clock).run()
            res["prepare_messages"] = msgs
            answer(res)
        except Exception as ex:
            answer({"ok": False, "error": f"{type(ex).__name__}: {ex}"})
    try:
        c.state(linuxcnc.STATE_OFF)
        c.wait_complete(2.0)
    except Exception:
        pass


if __name__ == "__main__":
    main()
