#!/usr/bin/env python3
"""LinuxCNC behind the nc-conform adapter protocol (docs/adapter-protocol.md).

Per scenario of the `linuxcnc` dialect: the parameters become a LinuxCNC machine configuration
(lcnc_machine.py), the program runs on LinuxCNC's own task and motion controller (simulator HAL,
headless, `lcnc_agent.py` as its display), the operator inputs are given through LinuxCNC's
Python interface at their times, every servo cycle is recorded with HAL's sampler, and `read`
answers with that recording as trace events (lcnc_trace.py).

LinuxCNC runs in real time and cannot be stopped and resumed at a condition the way the protocol's
`advance` asks. So a run goes to its end; `advance` stops where a condition began to hold in that
recording; an input the harness then gives (at the condition's time + its delay) is scheduled at
that time and the program is run again from the start with it, the events after the stop taken
from the new run. How far the condition's time moved between the runs and how late each input
was given are logged (stderr, and --log FILE as JSON lines): the achieved accuracy.

An input LinuxCNC has no counterpart for (dry run, machine lock, PLC answers, motor current,
parameter changes) is answered `unsupported`: the scenario is not applicable (skipped), never
passed. One LinuxCNC instance serves every scenario with the same machine configuration; a
scenario with other parameters restarts it.

Usage: lcnc_adapter.py [--user lcnc] [--lock /tmp/linuxcnc.lock] [--log FILE]
Standard library only; LinuxCNC (Debian's linuxcnc-uspace 2.9) must be installed.
"""

import argparse
import bisect
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import lcnc_machine  # noqa: E402
import lcnc_trace  # noqa: E402

PROTOCOL = "nc-conform-adapter/1"
# Inputs LinuxCNC (its task, GUIs and this simulator's HAL) can be given.
APPLICABLE = {"cycle_start", "reset", "feed_hold", "single_block", "optional_stop", "emergency_stop",
              "feed_override", "spindle_override", "spindle_stall"}
WHY_NOT = {
    "dry_run": "LinuxCNC has no dry run switch (LCNC-INP-02)",
    "machine_lock": "LinuxCNC has no machine lock switch (LCNC-INP-03)",
    "plc_answer": "LinuxCNC has no PLC handshake to answer (M functions complete at once)",
    "motor_current": "the simulator machine has no motor current to load",
    "set_param": "LinuxCNC's machine settings (INI) cannot change during a run",
}


def log(*a):
    print("lcnc-adapter:", *a, file=sys.stderr, flush=True)


def measured_lead(g, period_us):
    """The lead (µs) an input given as `g` (the agent's `given` record: sent, taken at `cycle`)
    shows, to give the next one of its kind that much before its time; None when it shows none.
    A reset's only where its effect was seen (the spindle stopping): its echo comes once the
    abort is done, long after it acted. Never a cycle start's: LinuxCNC takes a resume or a step
    only once held (a hold taking effect, a step standing done), so its time to be taken is the
    wait for that, and a cycle start sent that much earlier comes before the hold and is lost
    (cycles/g88, g331/single_block stopped for good in a full run with a 21 ms lead)."""
    name = g["input"]["name"]
    if name == "cycle_start":
        return None
    trusted = name not in ("reset", "emergency_stop") or g.get("acted") or (
        name == "emergency_stop" and g["input"].get("on"))
    if g["cycle"] > g["sent"] and not g.get("unacknowledged") and trusted:
        return (g["cycle"] - g["sent"]) * period_us
    return None


class Scenario:
    """One loaded scenario: its job, the inputs scheduled so far, the latest run's events and
    how far the harness has read them."""

    def __init__(self, job, cfg):
        self.job = job
        self.cfg = cfg
        self.inputs = []  # [{"t_us", "input", "after": (condition, t_stop) or None}]
        self.events = None
        self.pos = 0  # events[:pos] handed to the harness
        self.now = 0
        self.cut = None  # (t_us, texts delivered at t_us) where a new run takes over
        self.pending = []
        self.stale = True
        self.runs = 0
        self.t0_lead = 2
        self.stops = []  # [(condition, t_us)] where advance stopped
        self.interp_error = None
        self.ended = False
        self.leads = {}  # input name -> µs LinuxCNC's task took to take it in the last run
        self.final = []  # the last run's events
        self.out = []  # what `read` answers next: the last run once the run has ended


class Adapter:
    def __init__(self, args):
        self.args = args
        self.instance = None
        self.instance_key = None
        self.sc = None
        self.logf = open(args.log, "a") if args.log else None
        self.workdir = None
        self.serial = 0
        self.leads = {}  # input name -> µs LinuxCNC's task took to take it, last seen

    def record(self, obj):
        if self.logf:
            self.logf.write(json.dumps(obj) + "\n")
            self.logf.flush()

    # ---- the LinuxCNC instance ----
    def ensure_instance(self, ini, hal):
        key = (ini, hal)
        if self.instance is not None and self.instance_key == key and self.instance.alive():
            return
        self.close_instance()
        t = time.monotonic()
        self.instance = lcnc_machine.Instance(ini, hal, self.args.user, self.args.lock)
        self.instance_key = key
        log(f"LinuxCNC {self.instance.version} started in {time.monotonic() - t:.1f} s")
        self.record({"event": "start", "seconds": round(time.monotonic() - t, 2), "version": self.instance.version})

    def close_instance(self):
        if self.instance is not None:
            self.instance.close()
        self.instance = None
        self.instance_key = None

    # ---- protocol ----
    def hello(self, req):
        if req.get("protocol") != PROTOCOL:
            return {"ok": False, "protocol": PROTOCOL, "error": "unsupported protocol"}
        version = linuxcnc_version()
        if self.args.machine:
            version += f" (machine {self.args.machine}, {self.args.path_mode})"
        return {"ok": True, "protocol": PROTOCOL, "name": "linuxcnc", "version": version,
                "dialects": ["linuxcnc"]}

    def load(self, req):
        if req.get("dialect") != "linuxcnc":
            return {"ok": False, "unsupported": f"LinuxCNC does not run {req.get('dialect')}"}
        try:
            ini, hal, cfg = lcnc_machine.machine_config(req.get("params", []), self.args.path_mode, self.args.planner,
                                                        lcnc_machine.planner_of(linuxcnc_version(), self.args.planner))
        except lcnc_machine.NotApplicable as e:
            return {"ok": False, "unsupported": f"not applicable: {e}"}
        self.ensure_instance(ini, hal)
        job = {k: req[k] for k in ("program", "sample_us", "time_limit_us", "auto_cycle_start")}
        self.sc = Scenario(job, cfg)
        path = os.path.join(self.instance.dir, "program.ngc")
        with open(path, "w") as f:
            f.write(req["program"])
        os.chmod(path, 0o644)
        self.sc.path = path
        self.sc.interp_error = interp_error(path, req["program"])
        return {"ok": True}

    def input(self, req):
        sc = self.sc
        if sc is None:
            return {"ok": False, "error": "no program loaded"}
        inp = req["input"]
        name = inp.get("name")
        if name not in APPLICABLE:
            return {"ok": False, "unsupported": "not applicable: " + WHY_NOT.get(name, f"no LinuxCNC counterpart of `{name}`")}
        t = int(req["t_us"])
        if t < sc.now:
            return {"ok": False, "error": f"input at {t} µs is before the clock ({sc.now} µs)"}
        after = sc.stops[-1] if sc.stops and sc.events is not None else None
        sc.inputs.append({"t_us": t, "input": inp, "after": after})
        sc.inputs.sort(key=lambda i: i["t_us"])
        if sc.events is not None:
            # a run already delivered up to now: the next advance runs again with this input
            sc.stale = True
            delivered = [lcnc_trace.dumps(e) for e in sc.events[:sc.pos] if e["t_us"] == sc.now]
            sc.cut = (sc.now, delivered)
        return {"ok": True}

    def run(self):
        """Runs the program on LinuxCNC with the inputs scheduled so far; once more when an input
        was given late by more than two servo periods with a lead not measured before (the first
        reset or override of a session: its task latency, ~20-30 ms, is known only after it was
        given once), with the lead just measured (I2); a third time when that lead was an outlier
        and the input now came early by more than two periods (A3: the first spindle override of
        a session taken 82 ms after it was sent, the next 2 ms: given 80 ms early); and once more
        when the run's time 0 came more than two servo periods off the trace's (the inputs,
        counted from it, stood off the trace's clock by as much: a feed hold 50 ms late under
        load moved g84/overrides_and_feed_hold's stop, and its cycle start, found on it, came
        50 ms late in the run that followed)."""
        P = self.sc.cfg["period_us"]
        known = set(self.leads)
        res = self.run_once()
        if "events" not in res:
            return res
        retime = {i["input"] for i in res["inputs"] if abs(i["late_us"]) > 2 * P
                  and i["input"] not in known and i["input"] in self.leads}
        if retime:
            log(f"run again with the measured leads of {sorted(retime)}")
            res = self.run_once()
            if "events" not in res:
                return res
            early = {i["input"] for i in res["inputs"] if i["input"] in retime and i["late_us"] < -2 * P}
            if early:
                log(f"run again: the leads of {sorted(early)} were outliers (given early now)")
                res = self.run_once()
                if "events" not in res:
                    return res
        if abs(res.get("t0_late_us") or 0) > 2 * P:
            log(f"run again: time 0 came {res['t0_late_us'] / 1000:g} ms off the trace's")
            res = self.run_once()
        return res

    def run_once(self):
        """One run of the program on LinuxCNC with the inputs scheduled so far."""
        sc = self.sc
        inst = self.instance
        out = os.path.join(inst.dir, "recording.txt")
        req = {
            "op": "run", "program": sc.path, "out": out,
            "inputs": [{"t_us": i["t_us"], "input": i["input"],
                        "lead_us": self.leads.get(i["input"]["name"], 2 * sc.cfg["period_us"])} for i in sc.inputs],
            "time_limit_us": sc.job["time_limit_us"], "auto_cycle_start": sc.job["auto_cycle_start"],
            "t0_lead": sc.t0_lead, "cfg": sc.cfg, "hold_ms": 500,
            "first_line_acts": lcnc_trace.Program(sc.job["program"]).first_line_acts(),
            "budget_us": min(sc.job["time_limit_us"], int(self.args.max_run_s * 1e6)),
        }
        t = time.monotonic()
        res = inst.call(req)
        sc.runs += 1
        if not res.get("ok"):
            raise RuntimeError("LinuxCNC run failed: " + res.get("error", "?") + "\n" + inst.log_tail(800))
        if "not_applicable" in res:
            return res
        if res["end"]["reason"] == "over_budget":
            if self.args.keep:  # the agent's log says why (its task states)
                os.makedirs(self.args.keep, exist_ok=True)
                with open(os.path.join(self.args.keep, f"run{self.serial:04d}.over_budget.agent.json"), "w") as f:
                    json.dump(res, f)
                self.serial += 1
            return {"not_applicable": f"LinuxCNC's run went past the adapter's budget of {self.args.max_run_s:g} s "
                                      f"of machine time (--max-run-s) before the scenario's own end"}
        rows = lcnc_trace.read_rows(out, sc.cfg["period_us"])
        if not rows:
            raise RuntimeError("nothing recorded: " + inst.log_tail(800))
        res["interp_error"] = sc.interp_error
        tr = lcnc_trace.Trace(sc.job["program"], rows, res, sc.cfg, sc.job["sample_us"])
        events = tr.build()
        if self.args.keep:
            os.makedirs(self.args.keep, exist_ok=True)
            stem = os.path.join(self.args.keep, f"run{self.serial:04d}")
            self.serial += 1
            shutil.copy(out, stem + ".rec.txt")
            with open(stem + ".agent.json", "w") as f:
                json.dump(res, f)
            with open(stem + ".jsonl", "w") as f:
                f.write("".join(lcnc_trace.dumps(e) + "\n" for e in events))
        sc.t0_lead = max(0, tr.t0 - res["c_run"])
        late = []
        P = sc.cfg["period_us"]
        for g in res.get("given", []):
            if not g.get("auto"):
                late.append({"input": g["input"]["name"], "late_us": (g["cycle"] - g["due"]) * P,
                             "t_us": (g["cycle"] - tr.t0) * P, "taken_us": (g["cycle"] - g["sent"]) * P,
                             "due_t_us": (g["due"] - tr.t0) * P})
                lead = measured_lead(g, P)
                if lead is not None:
                    self.leads[g["input"]["name"]] = lead
        info = {"event": "run", "run": sc.runs, "seconds": round(time.monotonic() - t, 2),
                "end": res["end"]["reason"], "events": len(events), "inputs": late}
        if res.get("t0") is not None:
            # the agent's time 0 (the inputs' times count from it) after the trace's: inputs late by it
            info["t0_late_us"] = (res["t0"] - tr.t0) * P
        log(json.dumps(info))
        self.record(info)
        return {"events": [parse_raw(e) for e in events], "inputs": late, "t0_late_us": info.get("t0_late_us")}

    def advance(self, req):
        sc = self.sc
        if sc is None:
            return {"ok": False, "error": "no program loaded"}
        if sc.stale:
            res = self.run()
            if "not_applicable" in res:
                return {"ok": False, "unsupported": "not applicable: " + res["not_applicable"]}
            new = res["events"]
            sc.final = new
            if sc.cut is not None:
                t_cut, delivered = sc.cut
                self.accuracy(new)
                keep = []
                for e in new:
                    if e["t_us"] > t_cut or (e["t_us"] == t_cut and e["kind"] != "sample"
                                             and lcnc_trace.dumps(e) not in delivered):
                        keep.append(e)
                if not any(e["kind"] == "end" for e in keep):
                    # the new run ended before the time already delivered (its start moved): its
                    # end closes the run there, not never (the harness would wait to its limit)
                    ends = [dict(e, t_us=max(e["t_us"], t_cut)) for e in new if e["kind"] == "end"]
                    keep += ends[-1:]
                sc.events = sc.events[:sc.pos] + keep
            else:
                sc.events = new
            sc.stale = False
        until = int(req["until_us"])
        conds = req.get("stop_on", [])
        trackers = [Tracker(c) for c in conds]
        for tr in trackers:
            tr.prime(sc.events[:sc.pos])
        # A condition's onsets are told apart by their order in the run, not by their µs: a run
        # again (for an input given since) repeats the onsets already stopped on a servo period or
        # a few later or earlier (LinuxCNC's timing varies from run to run), and one moved past
        # the stop must not count as the next occurrence (g331/single_block on a slower machine:
        # the second stop came 1 ms later in the re-run, was taken for the third, and the third's
        # cycle start, given 1 ms after the second's, was lost). The n-th onset of this run is new
        # when fewer than n were stopped on.
        told = [sum(1 for c, _ in sc.stops if same_condition(c, cond)) for cond in conds]
        onsets = [onset_times(cond, sc.final or sc.events) for cond in conds]
        i = sc.pos
        while i < len(sc.events):
            e = sc.events[i]
            if e["t_us"] >= until and e["kind"] != "end":
                break
            for k, tr in enumerate(trackers):
                hit = tr.see(e)
                if hit is not None and bisect.bisect_right(onsets[k], hit) > told[k]:
                    sc.pending += sc.events[sc.pos:i + (0 if hit < e["t_us"] else 1)]
                    sc.pos = i + (0 if hit < e["t_us"] else 1)
                    sc.now = max(sc.now, hit)
                    sc.stops.append((conds[k], hit))
                    return {"ok": True, "now_us": sc.now, "stopped_on": k, "ended": False}
            i += 1
            if e["kind"] == "end":
                break
        sc.pending += sc.events[sc.pos:i]
        sc.pos = i
        ended = bool(sc.pending) and sc.pending[-1]["kind"] == "end" or (
            sc.pos > 0 and sc.events[sc.pos - 1]["kind"] == "end")
        if ended:
            sc.now = max(sc.now, sc.events[sc.pos - 1]["t_us"])
            sc.out = list(sc.final)
        else:
            sc.now = max(sc.now, until)
        return {"ok": True, "now_us": sc.now, "stopped_on": None, "ended": ended}

    def accuracy(self, new):
        """How far the condition the last input waited for moved in the new run (the time it was
        given at is the first run's)."""
        sc = self.sc
        last = sc.inputs and max((i for i in sc.inputs if i["after"]), key=lambda i: i["after"][1], default=None)
        if not last:
            return
        cond, t_stop = last["after"]
        tr = Tracker(cond)
        seen = [tr.see(e) for e in new]
        onsets = [h for h in seen if h is not None]
        nearest = min(onsets, key=lambda h: abs(h - t_stop)) if onsets else None
        info = {"event": "rerun", "condition": cond, "first_run_us": t_stop,
                "this_run_us": nearest, "moved_us": None if nearest is None else nearest - t_stop}
        log(json.dumps(info))
        self.record(info)

    def read(self, req):
        """Nothing until the run has ended, then the last LinuxCNC run whole: it had every input
        at the time the harness gave it; the runs before it (that found the conditions' times)
        differ from it by the inputs' timing (a feed hold taken 3 ms earlier holds 15 µm
        earlier), so events spliced from two runs would show the machine jumping between them
        (cycles/g81_feed_hold's hold: Z -3.085 then -3.07 mm)."""
        sc = self.sc
        if sc is None:
            return '{"ok":true,"events":[]}'
        sc.pending = []
        ev, sc.out = sc.out, []
        return '{"ok":true,"events":[' + ",".join(lcnc_trace.dumps(e) for e in ev) + "]}"

    def reset(self, req):
        self.sc = None
        return {"ok": True}

    def serve(self):
        for line in sys.stdin:
            if not line.strip():
                continue
            try:
                req = json.loads(line)
            except ValueError:
                self.reply({"ok": False, "error": "not JSON"})
                continue
            op = req.get("op")
            try:
                if op == "quit":
                    self.reply({"ok": True})
                    break
                handler = getattr(self, op, None) if op in ("hello", "load", "input", "advance", "read", "reset") else None
                if handler is None:
                    self.reply({"ok": False, "error": f"unknown op {op!r}"})
                    continue
                ans = handler(req)
                self.reply(ans)
            except Exception as ex:  # LinuxCNC failed: say why, keep serving
                log(f"{type(ex).__name__}: {ex}")
                self.reply({"ok": False, "error": f"{type(ex).__name__}: {ex}"})
        self.close_instance()

    def reply(self, ans):
        sys.stdout.write((ans if isinstance(ans, str) else json.dumps(ans)) + "\n")
        sys.stdout.flush()


def parse_raw(e):
    """An event object with its Raw numbers kept (events are re-serialised as written)."""
    return e


def same_condition(a, b):
    return json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


def onset_times(cond, events):
    """Every µs at which `cond` begins to hold in a run's events, in order."""
    tr = Tracker(cond)
    return [h for h in (tr.see(e) for e in events) if h is not None]


class Tracker:
    """One `stop_on` condition over trace events: the time it begins to hold, or None."""

    def __init__(self, cond):
        self.c = cond
        self.last = None  # last sample value of the axis

    def prime(self, events):
        for e in events:
            if e["kind"] == "sample" and "axis" in self.c:
                self.last = (e["t_us"], float(e["axes"][self.c["axis"]].text))

    def see(self, e):
        c = self.c
        k = e["kind"]
        if "signal" in c:
            if k == "signal" and e["name"] == c["signal"] and e["value"] == int(c["value"]):
                return e["t_us"]
        elif "axis" in c:
            if k == "sample":
                x = float(e["axes"][c["axis"]].text)
                prev, self.last = self.last, (e["t_us"], x)
                if prev is None:
                    return None
                t_p, x_p = prev
                v = float(c["below"] if "below" in c else c["above"])
                crossed = (x < v <= x_p) if "below" in c else (x > v >= x_p)
                if crossed:
                    # the µs the axis passes the value, between the two servo samples
                    return int(math.ceil(t_p + (v - x_p) / (x - x_p) * (e["t_us"] - t_p)))
        elif "block" in c:
            if k == "block" and e["line"] == c["block"]:
                return e["t_us"]
        elif "phase" in c:
            if k == "phase" and e["name"] == c["phase"]:
                return e["t_us"]
        elif "function" in c:
            f = c["function"]
            if k == "function" and f"{e['letter']}{e['code']}" == f.upper():
                return e["t_us"]
        return None


def interp_error(path, program):
    """The line LinuxCNC's interpreter stops at, as its standalone `rs274` (the same
    interpreter; AXIS's preview) reports it: its message and the offending block's text, found in
    the program. LinuxCNC's task reports the message without the line. None: no error."""
    try:
        out = subprocess.run(["rs274", "-g", path], capture_output=True, text=True, timeout=30,
                             stdin=subprocess.DEVNULL)
    except (OSError, subprocess.TimeoutExpired):
        return None
    lines = [l for l in (out.stdout + out.stderr).splitlines() if l.strip() and l.strip() != "executing"]
    canon = re.compile(r"^\s*\d+ N\.\.\.\.\. ")
    text = [l for l in lines if not canon.match(l)]
    if out.returncode == 0 or len(text) < 2:
        return None
    message, block = text[-2].strip(), text[-1].strip()
    for n, l in enumerate(program.split("\n"), 1):
        if l.strip() == block:
            return {"message": message, "line": n}
    return {"message": message, "line": None}


def linuxcnc_version():
    try:
        out = os.popen("dpkg-query -W -f '${Version}' linuxcnc-uspace 2>/dev/null").read().strip()
        return out or "unknown"
    except OSError:
        return "unknown"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--user", default=os.environ.get("LCNC_USER", "lcnc"),
                    help="the ordinary user LinuxCNC runs as when started by root (default lcnc)")
    ap.add_argument("--lock", default="/tmp/linuxcnc.lock", help="flock file shared by LinuxCNC users")
    ap.add_argument("--log", default=os.environ.get("LCNC_ADAPTER_LOG"),
                    help="append the runs' timing and accuracy here (JSON lines)")
    ap.add_argument("--max-run-s", type=float, default=float(os.environ.get("LCNC_MAX_RUN_S", 120)),
                    help="stop a LinuxCNC run after this much machine time (default 120 s); a scenario "
                         "that needs longer is not applicable")
    ap.add_argument("--path-mode", type=lcnc_machine.path_mode, default="G64",
                    help="power-on path mode: LinuxCNC's default G64 (blending, with its P and Q "
                         "tolerances if given: `G64 P0.005`), G61 (exact path) or G61.1 (exact stop)")
    ap.add_argument("--machine", default=None,
                    help="the user's machine these parameters came from (its INI file's name): "
                         "named in the identity the adapter gives (`hello`), so in every report")
    ap.add_argument("--planner", choices=["default", "exact"], default="default",
                    help="LinuxCNC's planner look-ahead: its default, or `exact` "
                         "([TRAJ] ARC_BLEND_OPTIMIZATION_DEPTH = 1: no tangent joins of colinear "
                         "moves, no 10 %% acceleration cut at corners, in G61 and in canned cycles)")
    ap.add_argument("--keep", default=os.environ.get("LCNC_ADAPTER_KEEP"),
                    help="keep every run's recording, agent log and trace in this folder")
    Adapter(ap.parse_args()).serve()


if __name__ == "__main__":
    main()
