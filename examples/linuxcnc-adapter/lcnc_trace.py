"""A LinuxCNC run as an nc-conform trace (docs/trace-format.md, `nc-conform-trace/1`).

Input: the HAL sampler's recording (one row per servo cycle, columns `COLUMNS`, the cycle count
from the machine's `servo_clock`) and the agent's log (LinuxCNC's task states, operator messages,
the inputs as given, each stamped with its servo cycle). Output: trace events as JSON objects
with exact decimal numbers.

The mapping (examples/linuxcnc-adapter/README.md says it for users):

- **time 0** is the first servo cycle in which the program changes an output (an axis moves, the
  spindle turns on or changes speed, the motion line or type changes, coolant): the reference's
  t = 0 is its first block. An event first seen in row r is at (r - t0) x period; a `sample` at t
  shows row t0 + t/period - 1, the state before the events at t (as the reference's samples).
- **samples**: joint feedback X Y Z (trivkins, machine = program coordinates, mm); spindle speed
  = the speed the sim spindle turns at (after the ramp, signed); angle = the sim encoder's
  revolutions modulo 1 x 360 (its index is angle 0).
- **functions**: from the spindle's HAL pins: on forward M3, on reverse M4, off M5, a reversal
  M5 then M3/M4 (LinuxCNC's G84/G74 and G86/G88 stop and restart it with these canonical calls);
  inside G33.1 the reversals are motion's own (no function) and the direction taken again at its
  end is M3/M4; S with the first start and every change of the programmed speed; M2/M30 at the
  program end; M8/M7/M9 from the coolant pins. Each function has its strobe and FIN at the same
  µs: LinuxCNC has no completion handshake (the dialect's `plc.fin_ms` = 0).
- **signals**: STL (program running, not paused), SPL (paused: feed hold, single-block step, M0;
  raised where the hold took effect: the standstill that lasts until the program goes on, DEC-154),
  ZSP (spindle standing for `plc.zsp_ms`, falling when it turns: a stalled spindle started stays
  at zero speed), ESP (LinuxCNC's E-stop state).
- **blocks**: a line starts when its motion starts (`motion.program-line`, read with the positions
  of the servo cycle it belongs to: `LAGGING`; a subroutine's body after its call), or with the first
  spindle/coolant change it makes; lines without an observable action start with the next one
  that has it.
- **phases** (in cycles only, as the reference): from the cycle's line, motion type and the tool
  axis' direction: see `Phases`.
- **alarms**: LinuxCNC's error messages, coded as the dialect codes their texts (`alarm_code`);
  LinuxCNC's E-stop is NC-1030.
"""

import re

COLUMNS = ["n", "X", "Y", "Z", "rpm", "revs", "speed_cmd", "clock", "on", "fwd", "rev", "at_speed",
           "index", "inpos", "flood", "mist", "line", "mtype"]
SIGNALS = ["MF", "SF", "TF", "FIN", "F76.3", "RGTAP", "SPPOS", "SPPOSA", "RGSPP", "RGSPM", "SPL", "STL",
           "ESP", "ZSP"]
MOTION_TRAVERSE, MOTION_FEED = 1, 2
# servo cycles between motion going on after a cycle start and the agent seeing the task's echo
# of it (cycles/g81_feed_hold, adapter17-6: motion on at the cycle the echo was stamped)
ACK_LAG_CYCLES = 5


def dec(x, digits):
    """x rounded to `digits` decimals as exact decimal text (no exponent, no trailing zeros)."""
    q = round(x * 10**digits)
    if q == 0:
        return "0"
    sign = "-" if q < 0 else ""
    q = abs(q)
    whole, frac = divmod(q, 10**digits)
    s = f"{whole}.{frac:0{digits}d}".rstrip("0").rstrip(".")
    return sign + s


class Raw:
    """A JSON value written as is (an exact decimal)."""

    def __init__(self, text):
        self.text = text


def dumps(obj):
    """JSON text with Raw numbers as written."""
    import json

    if isinstance(obj, Raw):
        return obj.text
    if isinstance(obj, dict):
        return "{" + ",".join(json.dumps(k) + ":" + dumps(v) for k, v in obj.items()) + "}"
    if isinstance(obj, list):
        return "[" + ",".join(dumps(v) for v in obj) + "]"
    return json.dumps(obj, ensure_ascii=False)


# Motion's pins written from its status of the servo cycle before: its controller writes the HAL
# (control.c `output_to_hal`: motion.program-line = emcmotStatus->id, motion.motion-type =
# emcmotStatus->motionType) before it takes the planner's status of this cycle (`update_status`),
# while the joints' positions written there are this cycle's. A new line or motion type shows one
# servo period after its first position change.
LAGGING = ("line", "mtype")


def read_rows(path, period_us):
    """The recording as rows of numbers keyed by servo cycle (from the clock column), motion's
    line and motion type moved back to the cycle of the positions they belong to (`LAGGING`)."""
    rows = []
    with open(path) as f:
        for line in f:
            v = line.split()
            if len(v) != len(COLUMNS):
                continue  # halsampler's "overrun" line when the FIFO's count continues
            r = dict(zip(COLUMNS, (float(x) for x in v)))
            r["cycle"] = int(round(r["clock"] * 1e6 / period_us))
            rows.append(r)
    for a, b in zip(rows, rows[1:]):
        if b["cycle"] == a["cycle"] + 1:
            for k in LAGGING:
                a[k] = b[k]
    return rows


# LinuxCNC interpreter texts and the dialect's codes for them (docs/rules/linuxcnc.md).
CODES = [
    (r"zero feed rate", "NC-1091"),
    (r"R less than", "NC-1092"),
    (r"R clearance plane unspecified", "NC-1093"),
    (r"zero repeats", "NC-1094"),
    (r"[Ss]pindle (not turning|turning (counter)?clockwise)|not turning in", "NC-1095"),
    (r"missing with|unspecified in|word missing", "NC-1096"),
    (r"[Uu]nknown [gm] code", "NC-1090"),
]


def alarm_code(text):
    for pat, code in CODES:
        if re.search(pat, text):
            return code
    return "NC-1090"


# ---- the program text: which lines are cycles and what they carry ----

WORD = re.compile(r"([A-Za-z])\s*([-+]?\d*\.?\d+)")
OWORD = re.compile(r"^\s*(?:/\s*)?(?:[Nn]\d+\s*)?[Oo]\s*(\d+|<[^>]*>)\s*(sub|endsub|call)\b", re.I)


def words(line):
    """The words of one line, comments removed: [(letter, value)]."""
    code = re.sub(r"\([^)]*\)", "", line.split(";")[0])
    return [(l.upper(), float(v)) for l, v in WORD.findall(code)]


class Program:
    """Per line: its text, the motion mode after it, its M and S words, whether it is a cycle."""

    CYCLES = {73, 74, 76, 81, 82, 83, 84, 85, 86, 87, 88, 89}

    def __init__(self, text):
        self.lines = text.split("\n")
        self.kind = {}
        self.m = {}
        self.s = {}
        self.p = {}
        self.plane = {}
        self.sync = {}
        mode, plane = None, 17
        for i, raw in enumerate(self.lines, 1):
            ws = words(raw)
            axes = any(l in "XYZR" for l, _ in ws)
            g = [v for l, v in ws if l == "G"]
            for v in g:
                if v in (17, 18, 19):
                    plane = int(v)
                if v in (0, 1, 2, 3, 33, 33.1, 76, 80) or int(v) in self.CYCLES and v == int(v):
                    mode = v
            self.plane[i] = plane
            self.m[i] = [int(v) for l, v in ws if l == "M"]
            self.s[i] = [v for l, v in ws if l == "S"]
            self.p[i] = next((v for l, v in ws if l == "P"), 0.0)
            self.sync[i] = 33 in g
            if 33.1 in g:
                self.kind[i] = "g331"
            elif 33 in g:
                self.kind[i] = "g33"
            elif 76 in g:
                self.kind[i] = "g76"
            elif mode is not None and mode == int(mode) and int(mode) in self.CYCLES and (axes or any(v == mode for v in g)):
                self.kind[i] = "cycle%d" % int(mode)

    def text(self, line):
        return self.lines[line - 1].strip() if 0 < line <= len(self.lines) else ""

    def first_line_acts(self):
        """Whether the program's first block turns the spindle or coolant on or names an axis:
        an output changes when LinuxCNC runs it (lcnc_agent's single-block start)."""
        for line in range(1, len(self.lines) + 1):
            if self.is_block(line):
                ws = words(self.lines[line - 1])
                return any(m in (3, 4, 7, 8) for m in self.m[line]) or any(l in "XYZ" for l, _ in ws)
        return False

    def is_block(self, line):
        t = self.text(line)
        return bool(t) and not t.startswith(("(", ";", "%"))

    def call_of(self, line, after):
        """When `line` is inside an o-word subroutine's body: the first line at or after `after`
        that calls that subroutine (its body runs when the call is executed, LinuxCNC's motion
        then names the body's line), else None."""
        name = None
        for i in range(1, min(line, len(self.lines)) + 1):
            m = OWORD.match(self.lines[i - 1])
            if m and m.group(2).lower() == "sub":
                name = m.group(1).lower()
            elif m and m.group(2).lower() == "endsub" and i < line:
                name = None
        if name is None:
            return None
        for i in range(max(after, 1), len(self.lines) + 1):
            m = OWORD.match(self.lines[i - 1])
            if m and m.group(1).lower() == name and m.group(2).lower() == "call":
                return i
        return None


def tool_axis(plane):
    return {17: "Z", 18: "Y", 19: "X"}[plane]


class Trace:
    """Builds the events of one run."""

    def __init__(self, program_text, rows, agent, cfg, sample_us):
        self.prog = Program(program_text)
        self.rows = rows
        self.agent = agent
        self.P = cfg["period_us"]
        self.zsp_cycles = max(1, int(round(cfg.get("zsp_ms", 8) * 1000 / self.P)))
        self.sample_us = sample_us
        self.events = []  # (t_us, order, obj)
        self.seq = 0
        self.levels = {s: 0 for s in SIGNALS}
        self.by_cycle = {r["cycle"]: r for r in rows}
        self.t0 = self.find_t0()
        self.acted()
        self.next_block = 1
        self.blocks = 0
        self.alarms = 0
        self.stopped_by = None
        self.hold_at = None
        # the first servo cycle a reset or E-stop was sent: motion aborts from about there (its
        # stop is the abort's, not a phase of the cycle nor a feed hold taking effect)
        self.abort_sent = min((g["sent"] for g in agent.get("given", []) if "sent" in g
                               and g["input"]["name"] in ("reset", "emergency_stop") and g["input"].get("on", True)),
                              default=None)

    def acted(self):
        """A reset or E-stop acts before LinuxCNC's task reports it taken (its echo comes once the
        abort is done, up to ~150 ms later): the spindle going off between the command and that
        report marks when it acted."""
        for g in self.agent.get("given", []):
            name = g["input"]["name"]
            if name not in ("reset", "emergency_stop") or "sent" not in g or not g["input"].get("on", True):
                continue
            prev = None
            for r in self.rows:
                if g["sent"] < r["cycle"] <= g["cycle"] and prev is not None and prev["on"] and not r["on"]:
                    g["cycle"] = r["cycle"]
                    g["acted"] = True
                    break
                prev = r

    # --- helpers ---
    def find_t0(self):
        keys = ("X", "Y", "Z", "on", "speed_cmd", "line", "mtype", "flood", "mist")
        first = self.rows[0]
        c_run = self.agent.get("c_run", first["cycle"])
        states = self.agent.get("states") or [{"cycle": c_run, "paused": False}]
        pause = next((st["cycle"] for st in states if st["paused"]), None)
        for r in self.rows:
            if pause is not None and r["cycle"] >= pause:
                break  # held before any output (a single-block start): the program started then
            if r["cycle"] >= c_run and any(abs(r[k] - first[k]) > 1e-9 for k in keys):
                return r["cycle"]
        return states[0]["cycle"]

    def t(self, cycle):
        return max(0, (cycle - self.t0) * self.P)

    def emit(self, t, obj):
        self.seq += 1
        self.events.append((t, self.seq, dict({"t_us": t}, **obj)))

    def signal(self, t, name, value):
        if self.levels[name] != value:
            self.levels[name] = value
            self.emit(t, {"kind": "signal", "name": name, "value": value})

    def function(self, t, letter, code):
        self.emit(t, {"kind": "function", "letter": letter, "code": int(code)})
        strobe = {"M": "MF", "S": "SF", "T": "TF"}[letter]
        for name, v in ((strobe, 1), ("FIN", 1), (strobe, 0), ("FIN", 0)):
            self.emit(t, {"kind": "signal", "name": name, "value": v})

    def block(self, t, upto):
        """Block events for every program line up to `upto` not started yet."""
        while self.next_block <= min(upto, len(self.prog.lines)):
            line = self.next_block
            self.next_block += 1
            if self.prog.is_block(line):
                self.emit(t, {"kind": "block", "line": line, "text": self.prog.text(line)})
                self.blocks += 1
                for sv in self.prog.s.get(line, []):
                    self.function(t, "S", round(sv))

    def next_sync_line(self):
        """The first line not started yet with a synchronised move (G33, G33.1, G76)."""
        for line in range(self.next_block, len(self.prog.lines) + 1):
            if self.prog.kind.get(line) in ("g331", "g33", "g76"):
                return line
        return None

    def line_with_m(self, codes):
        """The first line not started yet that has one of the M codes."""
        for line in range(self.next_block, len(self.prog.lines) + 1):
            if any(m in codes for m in self.prog.m.get(line, [])):
                return line
        return None

    # --- the run, row by row ---
    def build(self):
        """The events of the run, ended by `end` at the run's end (see `end_cycle`)."""
        rows = [r for r in self.rows if r["cycle"] >= self.t0 - 1]
        if not rows:
            rows = self.rows[-1:]
        end_c, reason = self.end_cycle(rows)
        given = sorted(self.agent.get("given", []), key=lambda g: g["cycle"])
        states = list(self.agent.get("states", []))
        msgs = [m for m in self.agent.get("messages", []) if m["kind"] in (1, 11)]  # NML/OPERATOR_ERROR
        self.signal(0, "STL", 1)
        if abs(rows[0]["rpm"]) < 1e-9 and not rows[0]["on"]:
            self.signal(0, "ZSP", 1)
        self.phase = "idle"
        self.cur = None
        self.g331_dir = None
        self.cycle_since = None
        self.still_since = None
        zero_since = None
        prev = rows[0]
        for r in rows[1:]:
            c = r["cycle"]
            if c > end_c:
                break
            t = self.t(c)
            while given and given[0]["cycle"] <= c:
                g = given.pop(0)
                tg = self.t(max(g["cycle"], self.t0))
                if not g.get("auto"):
                    self.emit(tg, {"kind": "input", "name": g["input"]["name"], "value": input_value(g["input"])})
                if g["input"]["name"] == "cycle_start":
                    self.pause_pending = False
                    if self.levels["SPL"]:
                        self.signal(tg, "SPL", 0)
                        self.signal(tg, "STL", 1)
                if g["input"]["name"] in ("reset", "emergency_stop"):
                    self.stopped_by = g["input"]["name"]
                    if g["input"].get("on"):
                        self.signal(tg, "ESP", 1)
                        self.alarm(tg, "NC-1030", "EMERGENCY STOP", None)
            while states and states[0]["cycle"] <= c:
                st = states.pop(0)
                if st["interp"] != 1 or st["paused"]:
                    if st["paused"]:
                        # paused from here; SPL where the hold took effect (below), as the
                        # reference reports a hold
                        self.pause_pending = True
                        self.step_done = bool(st.get("step"))
                        self.hold_at = self.hold_effect(st["cycle"], end_c)
                    else:
                        self.pause_pending = False
                        self.signal(t, "SPL", 0)
                        self.signal(t, "STL", 1)
                    if st["paused"]:
                        stop = self.line_with_m((0, 1, 60))
                        if stop is not None and self.next_block <= stop:
                            self.block(t, stop)
                            self.function(t, "M", [m for m in self.prog.m[stop] if m in (0, 1, 60)][0])

            while msgs and msgs[0]["cycle"] <= c:
                m = msgs.pop(0)
                line = re.search(r"[Ll]ine (\d+)", m["text"])
                line = int(line.group(1)) if line else None
                ie = self.agent.get("interp_error")
                if line is None and ie and ie["message"] == m["text"].strip():
                    line = ie["line"]
                self.alarm(t, alarm_code(m["text"]), m["text"].strip(), line)
            self.row(prev, r, t)
            if getattr(self, "pause_pending", False) and self.hold_at is not None and c >= self.hold_at:
                self.pause_pending = False
                if getattr(self, "step_done", False) and self.cur is not None and self.prog.kind.get(self.cur):
                    # a single-block step stands done: its line, a cycle, is over (the reference
                    # ends the cycle's phases as the block ends)
                    self.leave_cycle(t)
                self.signal(t, "SPL", 1)
                self.signal(t, "STL", 0)
            # ZSP: the spindle standing for plc.zsp_ms (it falls with a start command or motion)
            if abs(r["rpm"]) < 1e-9 and not (r["on"] and not prev["on"]):
                zero_since = c if zero_since is None else zero_since
                if c - zero_since + 1 >= self.zsp_cycles:
                    self.signal(t, "ZSP", 1)
            else:
                zero_since = None
                if abs(r["rpm"]) >= 1e-9:
                    self.signal(t, "ZSP", 0)
            prev = r
        self.finish_program(end_c, reason)
        last = [r for r in rows if r["cycle"] <= end_c] or rows[:1]
        self.samples(rows, end_c)
        self.end(end_c, reason, last[-1])
        self.events.sort(key=lambda e: (e[0], e[1]))
        return [e[2] for e in self.events]

    def alarm(self, t, code, message, line):
        o = {"kind": "alarm", "code": code, "message": message}
        if line is not None:
            o["line"] = line
        self.emit(t, o)
        self.alarms += 1

    def standstill_from(self, upto):
        """The first servo cycle of the standstill that lasts up to cycle `upto` (the first row in
        which no axis moved from the row before, as every row after it up to `upto`), or None
        when the axes moved into `upto`."""
        cycles = sorted(c for c in self.by_cycle if c <= upto)
        if not cycles or cycles[-1] != upto:
            return None
        since = None
        for a, b in zip(reversed(cycles[:-1]), reversed(cycles)):
            ra, rb = self.by_cycle[a], self.by_cycle[b]
            if any(abs(rb[k] - ra[k]) > 1e-9 for k in "XYZ"):
                break
            since = b
        return since

    def hold_effect(self, paused, end_c):
        """The servo cycle a pause reported at cycle `paused` took effect: where the axes came to
        the standstill that lasts until the program went on (the task left its paused state or a
        cycle start was taken) or the run's end; None when motion never held (it still moved when
        the program went on). LinuxCNC defers a pause inside a spindle-synchronised move (G33,
        G33.1, G76's passes run to their end: tp.c `tpGetFeedScale` pauses TC_SYNC_NONE and
        velocity-synchronised segments only) and while a move waits for at-speed or the index;
        the axes standing still in those waits is not yet the hold."""
        ends = [st["cycle"] for st in self.agent.get("states", []) if st["cycle"] > paused and not st["paused"]]
        ends += [g["cycle"] for g in self.agent.get("given", [])
                 if g["input"]["name"] == "cycle_start" and g["cycle"] is not None and g["cycle"] > paused]
        if self.abort_sent is not None:
            ends.append(self.abort_sent)
        resume = min(ends + [end_c])
        # the last row the machine stood in before it went on: the agent stamps a cycle start
        # when it sees the task's echo, up to a few servo cycles after motion went on
        upto = max((c for c in self.by_cycle if c <= resume), default=None)
        if upto is None:
            return None
        since = None
        for back in range(ACK_LAG_CYCLES + 1):
            since = self.standstill_from(upto - back)
            if since is not None:
                break
        if since is None:
            return None
        return max(since, paused)

    def end_cycle(self, rows):
        """The cycle the run ends at and its reason: a reset or E-stop where it acted, a time limit
        where it falls, else once nothing changes any more (the spindle stopped and ZSP reported)."""
        end = self.agent.get("end", {})
        reason = end.get("reason", "program_end")
        if reason == "reset":
            resets = [g["cycle"] for g in self.agent.get("given", []) if g["input"]["name"] == "reset"]
            return (max(resets[0], self.t0) if resets else end["cycle"]), reason
        if reason == "time_limit":
            if end.get("wall") or "limit_cycles" not in end:
                return end["cycle"], reason
            return self.t0 + end["limit_cycles"], reason
        if reason == "stopped":
            # held with nothing to release it: the run ends where the hold took effect
            holds = [st["cycle"] for st in self.agent.get("states", []) if st["paused"]]
            if not holds:
                return end["cycle"], reason
            at = self.hold_effect(holds[-1], end["cycle"])
            return max(at if at is not None else holds[-1], self.t0), reason
        if end.get("estop"):
            es = [g["cycle"] for g in self.agent.get("given", [])
                  if g["input"]["name"] == "emergency_stop" and g["input"].get("on")]
            return (es[0] if es else end["cycle"]), "alarm"
        keys = ("X", "Y", "Z", "rpm", "on", "fwd", "rev", "flood", "mist", "speed_cmd")
        last = rows[0]["cycle"]
        for a, b in zip(rows, rows[1:]):
            if b["cycle"] > end.get("settled", end.get("cycle", b["cycle"])) + 1:
                break
            if any(abs(a[k] - b[k]) > 1e-9 for k in keys):
                last = b["cycle"]
        stop = last + 1
        if not rows[-1]["on"]:
            stop = last + self.zsp_cycles
        if any(m["kind"] in (1, 11) for m in self.agent.get("messages", [])):
            reason = "alarm"
            first = min(m["cycle"] for m in self.agent["messages"] if m["kind"] in (1, 11))
            stop = max(stop if stop <= end.get("cycle", stop) else last + 1, first)
        return stop, reason

    def row(self, p, r, t):
        """Blocks, functions and phases from one servo cycle's change."""
        line = int(r["line"])
        if r["index"] and not p["index"]:
            # a synchronised move starts by arming the encoder index: its line has begun
            nxt = self.next_sync_line()
            if nxt is not None and nxt != self.cur:
                self.armed_from = self.cur
                self.enter_line(t, nxt, r)
        if line and line == getattr(self, "armed_from", None):
            pass  # motion still names the line before the armed synchronised move: not back to it
        elif line and line != self.cur:
            self.armed_from = None
            self.enter_line(t, line, r)
        elif line == self.cur:
            self.armed_from = None
        kind = self.prog.kind.get(self.cur) if self.cur else None
        sp, sr = spin(p), spin(r)
        if sp != sr and self.stopped_by:
            pass  # reset / E-stop: LinuxCNC stops the spindle itself, no function
        elif sp != sr:
            if kind == "g331" and sp != 0 and sr != 0:
                # the rigid tap's reversals are motion's own; its direction pins back to the
                # original sense (tp.c FINAL_REVERSAL, as the tap passes the start on the way
                # out) are the M3/M4 that restores it, where the reference gives it (DEC-149)
                if self.g331_dir and sr == self.g331_dir:
                    self.function(t, "M", 3 if sr > 0 else 4)
                    self.g331_dir = None
            elif kind and kind.startswith("cycle") and sp != 0 and sr != 0:
                # a direct reversal: a cycle's own reversals stop the spindle first (canon's
                # STOP_SPINDLE_TURNING, then START_SPINDLE_*: a servo period at rest between), so
                # this is the next line's M3/M4 (`G80 M4` after a G84), run before that line moves
                target = self.line_with_m((3 if sr > 0 else 4,))
                if target is not None:
                    self.block(t, target)
                self.function(t, "M", 3 if sr > 0 else 4)
            elif kind and kind.startswith("cycle") and self.cur_is_running(r):
                if sp != 0 and sr == 0 and self.program_end_stop():
                    self.pending_stop = t  # the cycle's own stop, or the program end's (below)
                elif sp != 0:
                    self.function(t, "M", 5)
                if sr != 0:
                    if getattr(self, "pending_stop", None) is not None:
                        self.function(self.pending_stop, "M", 5)
                        self.pending_stop = None
                    self.function(t, "M", 3 if sr > 0 else 4)
            else:
                self.spindle_change(t, sp, sr)
            if sr != 0 and sp == 0 and abs(r["rpm"]) >= 1e-9:
                # started and turning; a stalled spindle (T2) stays at zero speed
                self.signal(t, "ZSP", 0)
        for pin, on_code in (("flood", 8), ("mist", 7)):
            if p[pin] != r[pin]:
                code = on_code if r[pin] else 9
                target = self.line_with_m((code,))
                if target is not None:
                    self.block(t, target)
                self.function(t, "M", code)
        self.phases(p, r, t, kind)

    def program_end_stop(self):
        """A stop in a cycle with no M5 left in the program but an M2/M30: the cycle's own stop
        (it reverses through 0) when the spindle starts again, else the program end's stop (a
        `G80 M2` line moves nothing, so the cycle's line is still current): kept pending."""
        return self.line_with_m((5,)) is None and self.line_with_m((2, 30)) is not None

    def cur_is_running(self, r):
        """Still inside the cycle's line: before the interpreter's next line starts moving."""
        return self.next_block <= self.cur + 1

    def spindle_change(self, t, sp, sr):
        codes = {1: 3, -1: 4, 0: 5}
        want = [codes[sr]] if sp == 0 or sr == 0 else [5, codes[sr]]
        target = self.line_with_m(tuple(want[-1:]))
        if sr == 0 and target is None:
            end = self.line_with_m((2, 30))
            if end is not None:
                self.to_idle(t)
                self.block(t, end)
                self.function(t, "M", [m for m in self.prog.m[end] if m in (2, 30)][0])
                self.ended = True
                return
        if target is not None:
            self.block(t, target)
        for code in want:
            self.function(t, "M", code)

    def enter_line(self, t, line, r):
        if self.cur is not None and self.prog.kind.get(self.cur):
            self.leave_cycle(t)
        self.cur = line
        call = self.prog.call_of(line, self.next_block) if line >= self.next_block else None
        if call is not None:
            # a subroutine's body defined before its call: its lines were read (the reference
            # lists them as read), the call ran, then the body's line that LinuxCNC's motion
            # names (X2)
            self.block(t, call)
        elif line >= self.next_block:
            self.block(t, line)
        else:  # a line run again (an o-word loop or subroutine)
            self.next_block, saved = line, self.next_block
            self.block(t, line)
            self.next_block = saved
        kind = self.prog.kind.get(line)
        if kind in ("g331", "g33"):
            self.set_phase(t, "cutting")
            self.g331_dir = (spin(r) or None) if kind == "g331" else None
        elif kind:
            self.set_phase(t, "positioning")
        self.cycle_since = r["cycle"]
        self.still_since = None

    def leave_cycle(self, t):
        if self.prog.kind.get(self.cur) == "g331" and self.g331_dir:
            self.function(t, "M", 3 if self.g331_dir > 0 else 4)
            self.g331_dir = None
        self.to_idle(t)

    def to_idle(self, t):
        self.set_phase(t, "idle")

    def set_phase(self, t, name):
        if self.phase != name:
            self.phase = name
            self.emit(t, {"kind": "phase", "name": name})

    def phases(self, p, r, t, kind):
        if not kind or (self.abort_sent is not None and r["cycle"] >= self.abort_sent):
            return
        plane = self.prog.plane.get(self.cur, 17)
        ta = tool_axis(plane)
        d = r[ta] - p[ta]
        moving = any(abs(r[a] - p[a]) > 1e-9 for a in "XYZ")
        mtype = int(r["mtype"])
        ph = self.phase
        if kind == "g33":
            # as the reference: a G33 line is its cutting phase from its start (the index wait
            # included) to the next line
            if ph != "cutting":
                self.set_phase(t, "cutting")
            return
        if kind == "g331":
            if ph == "cutting" and self.g331_dir and r["rpm"] * self.g331_dir < 0:
                self.set_phase(t, "retract")
            return
        if kind == "g76":
            if mtype == MOTION_FEED and moving and ph != "cutting":
                self.set_phase(t, "cutting")
                self.cut_from = r["Z"]
            elif ph == "cutting" and abs(r["X"] - p["X"]) > 1e-9 and (
                    mtype == MOTION_TRAVERSE or abs(r["Z"] - p["Z"]) < 1e-9) and (
                    abs(r["Z"] - getattr(self, "cut_from", r["Z"])) > 1e-6):
                # the rapid out begins with X once the pass has cut along Z: the pass's last
                # servo period may already show the traverse's type while only Z ends its cut
                # (a feed hold stops there), its first ones the feed's while X ends the infeed
                self.set_phase(t, "retract")
            elif ph == "retract" and moving and abs(r["Z"] - p["Z"]) > 1e-9 and abs(r["X"] - p["X"]) < 1e-9:
                self.set_phase(t, "positioning")
            return
        dwell_p = self.prog.p.get(self.cur, 0.0)
        if moving:
            self.hold_still = False
        elif getattr(self, "pause_pending", False) or self.levels["SPL"] or getattr(self, "hold_still", False):
            # a feed hold's standstill, until motion goes on after the cycle start, is not the
            # hole's bottom; but G88's own program stop comes after its dwell and its spindle stop
            # (rs274: DWELL, STOP_SPINDLE_TURNING, PROGRAM_STOP), and the task may report it in the
            # servo cycle the trace's dwell count ends or before: the spindle off, the dwell is over
            if ph == "dwell" and kind == "cycle88" and not r["on"]:
                self.set_phase(t, "retract")
            self.hold_still = True
            return
        if kind in ("cycle74", "cycle84") and plane != 17:
            # G84/G74 in G18/G19: LinuxCNC feeds in and out to its permuted points (DEC-166),
            # which need not move along the plane's tool axis, nor down it: the feed in is the
            # cutting (from its first period), a traverse after the feed out the next hole's
            # positioning, as the reference marks them; the bottom as any cycle's
            if ph == "positioning" and moving and mtype == MOTION_FEED:
                self.set_phase(t, "cutting")
            elif ph == "retract" and moving and mtype != MOTION_FEED:
                self.set_phase(t, "positioning")
            elif ph in ("cutting", "dwell"):
                self.bottom(t, r, ph, moving, dwell_p, kind)
            return
        if ph in ("positioning", "retract") and moving and mtype == MOTION_FEED and d < 0:
            self.set_phase(t, "cutting")
        elif ph == "retract" and moving and abs(d) < 1e-9 and kind.startswith("cycle"):
            # an L repeat (or the next hole of the same line) moving to its hole
            self.set_phase(t, "positioning")
        elif ph == "retract" and moving and d < 0 and kind in ("cycle73", "cycle83"):
            # a peck cycle's way back down (G83: the rapid to just above the last depth) is part
            # of the next peck, as the reference marks it
            self.set_phase(t, "cutting")
        elif ph == "cutting" and moving and d > 0:
            self.set_phase(t, "retract")
        elif ph in ("cutting", "dwell"):
            self.bottom(t, r, ph, moving, dwell_p, kind)

    def bottom(self, t, r, ph, moving, dwell_p, kind):
        """A cycle's bottom: the cut's standstill is its dwell (P, in the cycles that dwell) or
        its retract; the dwell ends when the motion goes on or its time is up."""
        if ph == "cutting" and not moving:
            if dwell_p > 0 and kind in ("cycle74", "cycle82", "cycle84", "cycle86", "cycle88", "cycle89"):
                self.set_phase(t, "dwell")
                self.still_since = r["cycle"]
            else:
                self.set_phase(t, "retract")
        elif ph == "dwell":
            if moving or r["cycle"] - self.still_since >= int(round(dwell_p * 1e6 / self.P)):
                self.set_phase(t, "retract")

    def finish_program(self, end_c, reason):
        """At the end: the cycle left, the program end's block and M2/M30 when LinuxCNC reached it."""
        t = self.t(end_c)
        if getattr(self, "pause_pending", False) and self.hold_at is not None and self.hold_at <= end_c:
            self.pause_pending = False
            self.signal(t, "SPL", 1)
            self.signal(t, "STL", 0)
        if getattr(self, "ended", False):
            return
        if self.cur is not None and self.prog.kind.get(self.cur):
            if reason == "program_end":
                self.leave_cycle(t)
        if reason == "program_end":
            end = self.line_with_m((2, 30))
            if end is not None:
                if getattr(self, "pending_stop", None) is not None:
                    t = self.pending_stop  # M2/M30 stopped the spindle: the end acted there
                self.block(t, end)
                self.function(t, "M", [m for m in self.prog.m[end] if m in (2, 30)][0])
            else:
                self.block(t, len(self.prog.lines))

    def samples(self, rows, end_c):
        if not self.sample_us:
            return
        step = self.sample_us
        k = 0
        while True:
            t = k * step
            c = self.t0 + t // self.P - 1
            if c >= end_c or t > self.t(end_c):
                break
            r = self.by_cycle.get(c)
            if r is not None:
                self.events.append((t, -1, sample(t, r)))
            k += 1
        # samples come before the events of their µs
        self.events.sort(key=lambda e: (e[0], e[1]))

    def end(self, end_c, reason, r):
        t = self.t(end_c)
        axes = {a: Raw(dec(r[a], 6)) for a in "XYZ"}
        modal = modal_codes(self.agent.get("gcodes"))
        self.emit(t, {
            "kind": "end", "reason": reason, "axes": axes, "command": dict(axes),
            "spindle": {"rpm": Raw(dec(r["rpm"], 3)), "angle_deg": Raw(dec(angle(r), 3))},
            "signals": {s: self.levels[s] for s in SIGNALS}, "modal": modal,
            "alarms": self.alarms, "blocks": self.blocks,
        })
        self.seq += 10**9  # nothing after the end


def spin(r):
    if not r["on"]:
        return 0
    return 1 if r["fwd"] else (-1 if r["rev"] else 0)


def angle(r):
    a = (r["revs"] % 1.0) * 360.0
    a = round(a, 3)
    return 0.0 if a >= 360.0 else a


def sample(t, r):
    return {"t_us": t, "kind": "sample", "axes": {a: Raw(dec(r[a], 6)) for a in "XYZ"},
            "spindle": {"rpm": Raw(dec(r["rpm"], 3)), "angle_deg": Raw(dec(angle(r), 3))}}


def input_value(inp):
    name = inp["name"]
    if "on" in inp:
        return "on" if inp["on"] else "off"
    if "percent" in inp:
        return f"{inp['percent']}%" if name != "motor_current" else f"{inp['source']} {inp['percent']}%"
    return ""


def modal_codes(gcodes):
    """LinuxCNC's active G codes (stat.gcodes, G x 10 per group) in the reference's order: plane,
    units, distance, feed mode, return mode, diameter mode, motion."""
    if not gcodes:
        return []
    # stat.gcodes groups: 1 motion, 2 plane, 4 units, 5 distance, 6 feed mode, 9 retract, 13 diameter
    out = []
    for i in (2, 4, 5, 6, 9, 13, 1):
        if i < len(gcodes) and gcodes[i] >= 0:
            g = gcodes[i]
            out.append(f"G{g // 10:02d}" if g % 10 == 0 else f"G{g // 10}.{g % 10}")
    return out
