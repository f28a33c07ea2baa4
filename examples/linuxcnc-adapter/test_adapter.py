#!/usr/bin/env python3
"""Tests of the LinuxCNC adapter's parts that need no LinuxCNC (run by
harness/tests/linuxcnc_adapter.rs, or `NC_CONFORM=target/debug/nc-conform python3 test_adapter.py`):

- the machine configuration written for a scenario's parameters reads back, through
  `nc-conform params --from-ini` (the project's own INI mapping), as those parameters;
- parameters LinuxCNC cannot have are not applicable, with the reason;
- a recording (servo-cycle rows) becomes trace events: time 0 at the first output, samples
  showing the state before their µs, M3/S with their block, the G33.1 phases, exact decimals;
- the stop conditions of `advance` over trace events, an axis crossing at its interpolated µs.
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import lcnc_adapter  # noqa: E402
import lcnc_machine  # noqa: E402
import lcnc_step  # noqa: E402
import lcnc_trace  # noqa: E402

NC = os.environ.get("NC_CONFORM", "nc-conform")


def from_ini(ini_text):
    """{id: value or {axis: value}} as `nc-conform params --from-ini` maps the INI."""
    with tempfile.NamedTemporaryFile("w", suffix=".ini", delete=False) as f:
        f.write(ini_text)
    try:
        out = subprocess.run([NC, "params", "--from-ini", f.name], capture_output=True, text=True, check=True).stdout
    finally:
        os.unlink(f.name)
    params, cur = {}, None
    for line in out.splitlines():
        code = line.split("#")[0].rstrip()
        if not code.strip() or code.strip() == "params:" or code.startswith("dialect:"):
            continue
        key, _, value = code.strip().partition(":")
        if line.startswith("    "):
            params[cur][key] = float(value)
        elif value.strip():
            params[key] = float(value)
        else:
            cur = key
            params[cur] = {}
    return params


def held(hold, then, then_at, end, end_reason="time_limit"):
    """The agent's record of a run held at cycle `hold` (feed hold given and taken there, the task
    paused) and then given `then` (an input, taken at `then_at`: (cycle, sent, due)), the task's
    next state at `then_at[0] + 1` (a reset: idle at its cycle - 1), ended at `end`."""
    c, sent, due = then_at
    after = {"cycle": c - 1, "interp": 1, "paused": False, "task": 4} if then == "reset" else \
        {"cycle": c + 1, "interp": 2, "paused": False, "task": 4}
    record = {"c_run": 105, "messages": [],
              "given": [{"cycle": hold, "sent": hold - 1, "due": hold, "input": {"name": "feed_hold"}},
                        {"cycle": c, "sent": sent, "due": due, "input": {"name": then}}],
              "states": [{"cycle": 109, "interp": 2, "paused": False, "task": 4},
                         {"cycle": hold, "interp": 3, "paused": True, "task": 4}, after],
              "end": {"reason": end_reason, "cycle": end}}
    if end_reason == "time_limit":
        record["end"]["settled"] = end
    return record


class MachineConfig(unittest.TestCase):
    CASES = [
        [],
        [{"id": "nc.spindle_max_rpm", "value": 4000}, {"id": "nc.feed_override_max_pct", "value": 150},
         {"id": "nc.spindle_override_min_pct", "value": 50}, {"id": "nc.spindle_override_max_pct", "value": 120}],
        [{"id": "nc.rapid_mm_min", "value": 3000}, {"id": "nc.rapid_ramp_ms", "value": 50},
         {"id": "nc.feed_max_mm_min", "value": 3000}, {"id": "nc.feed_ramp_ms", "value": 50},
         {"id": "nc.backlash_mm", "axis": "X", "value": 0.01}, {"id": "nc.period_us", "value": 2000}],
        [{"id": "nc.rapid_mm_min", "axis": "X", "value": 12000}, {"id": "nc.rapid_ramp_ms", "axis": "X", "value": 200}],
    ]

    def test_the_ini_reads_back_as_the_parameters(self):
        for params in self.CASES:
            ini, hal, cfg = lcnc_machine.machine_config(params)
            want = lcnc_machine.resolve(params)
            got = from_ini(ini)
            self.assertGreaterEqual(len(got), 9, got)
            for pid, value in got.items():
                with self.subTest(params=params, id=pid):
                    if pid == "nc.startup_g64_p_mm":
                        self.assertEqual(value, 0.0)  # the startup code's G64, without P
                    else:
                        self.assertEqual(value, want[pid])
            self.assertIn("setp limit_speed.maxv", hal)

    def test_the_spindle_ramp_is_the_hals(self):
        _, hal, _ = lcnc_machine.machine_config([{"id": "nc.spindle_ramp_ms", "value": 20000}])
        self.assertIn("setp limit_speed.maxv 300\n", hal)  # 6000 rpm in 20 s

    def test_the_machine_is_the_references(self):
        # at speed when the ramp reaches the command (a stalled spindle never is), and [TRAJ]
        # caps at the axes' combined limits (the reference's G0 is limited by its axes only)
        ini, hal, _ = lcnc_machine.machine_config([])
        self.assertIn("net spindle-speed-limited => near_speed.in2", hal)
        self.assertIn("setp near_speed.scale 1.0", hal)
        v = [float(l.split("=")[1]) for l in ini.splitlines() if l.startswith("MAX_VELOCITY")]
        cap = next(float(l.split("=")[1]) for l in ini.splitlines() if l.startswith("MAX_LINEAR_VELOCITY"))
        self.assertGreater(cap, max(v))
        exact, _, _ = lcnc_machine.machine_config([], "G61.1", "exact")
        self.assertIn("ARC_BLEND_OPTIMIZATION_DEPTH = 1", exact)
        self.assertIn("G61.1", exact)
        self.assertNotIn("ARC_BLEND_OPTIMIZATION_DEPTH", ini)

    def test_an_e_stop_acts_in_the_servo_cycle_it_is_armed_for(self):
        # HAL's E-stop (estop_at): every module loaded once (a second loadrt of one fails), the
        # comparator and its inverter first in the servo cycle, before motion reads its enable;
        # the spindle command cut between motion and the spindle's ramp
        _, hal, _ = lcnc_machine.machine_config([])
        lines = hal.splitlines()
        mods = [l.split()[1] for l in lines if l.startswith("loadrt ")]
        self.assertEqual(len(mods), len(set(mods)), mods)
        order = []
        for l in lines:
            if l.startswith("addf "):
                parts = l.split()
                if len(parts) > 3:
                    order.insert(int(parts[3]) - 1, parts[1])
                else:
                    order.append(parts[1])
        self.assertEqual(order[:3], ["estop_at", "estop_ok", "motion-command-handler"])
        self.assertLess(order.index("motion-controller"), order.index("estop_spindle"))
        self.assertLess(order.index("estop_spindle"), order.index("limit_speed"))
        self.assertLess(order.index("servo_clock"), order.index("sampler.0"))
        self.assertIn("net estop-ok estop_ok.out => motion.enable", hal)
        self.assertIn("net spindle-speed-cmd spindle.0.speed-out => estop_spindle.in0", hal)
        self.assertIn("net spindle-speed-estop estop_spindle.out => limit_speed.in", hal)
        self.assertIn("estop_at.in1", next(l for l in lines if l.startswith("net clock ")))
        # armed for cycle k (the agent's arm_estop), the comparator, on the clock the cycle before
        # left (servo_clock runs after it), trips in cycle k and not in k - 1
        for period_s in (0.001, 0.002, 0.00025):
            for k in (2, 8889, 10**7):
                in0 = agent_arm_estop(k, period_s)
                self.assertFalse((k - 2) * period_s > in0, (k, period_s))
                self.assertTrue((k - 1) * period_s > in0, (k, period_s))

    def test_an_exited_linuxcnc_not_yet_reaped_is_not_running(self):
        # another engineer's LinuxCNC left zombies for minutes; they hold nothing
        import time

        pid = os.fork()
        if pid == 0:
            os._exit(0)
        try:
            for _ in range(100):
                if lcnc_machine.zombie(pid):
                    break
                time.sleep(0.01)
            self.assertTrue(lcnc_machine.zombie(pid))
            self.assertFalse(lcnc_machine.zombie(os.getpid()))
        finally:
            os.waitpid(pid, 0)

    def test_a_users_machine_runs_as_its_ini_maps(self):
        # `scripts/linuxcnc-conform --ini`: what params --from-ini writes of a machine is a machine
        # the adapter can set up, also when its cutting time constant is not whole ms (166 mm/s
        # over 1500 mm/s^2: 110.667 ms, written 111) and its [TRAJ] caps lie below the axes'.
        axes = "".join(f"[AXIS_{a}]\nMAX_VELOCITY = 166\nMAX_ACCELERATION = 1500\n" for a in "XYZ")
        for traj in ("", "MAX_LINEAR_VELOCITY = 100\nMAX_LINEAR_ACCELERATION = 1000\n"):
            got = from_ini("[TRAJ]\nCOORDINATES = X Y Z\nLINEAR_UNITS = mm\n" + traj + axes)
            params = [{"id": k, "axis": a, "value": x} for k, v in got.items()
                      for a, x in (v.items() if isinstance(v, dict) else [(None, v)])]
            with self.subTest(traj=traj):
                ini, _, _ = lcnc_machine.machine_config(params)
                if traj:
                    self.assertIn("MAX_VELOCITY = 100\n", ini)

    def test_the_startup_code_gives_the_power_on_path_mode(self):
        def mode(code):
            return lcnc_machine.startup_path_mode(f"[EMC]\nX = 1\n[RS274NGC]\nRS274NGC_STARTUP_CODE = {code}\n")

        # LinuxCNC's sample configurations write these
        self.assertEqual(mode("G17 G21 G40 G43H0 G54 G64P0.005 G80 G90 G94 G97 M5 M9"), "G64 P0.005")
        self.assertEqual(mode("G18 G21 G40 G49 G54 G80 G90 G94 G8 M9 M5 G64 P0.005"), "G64 P0.005")
        self.assertEqual(mode("G21 G61.1 (not G64 in a comment)"), "G61.1")
        self.assertEqual(mode("G64 G61"), "G61")
        self.assertIsNone(mode("M52 P1"))
        self.assertIsNone(lcnc_machine.startup_path_mode("[RS274NGC]\nPARAMETER_FILE = x.var\n"))
        self.assertEqual(lcnc_machine.path_mode("g64 p0.01 q0.005"), "G64 P0.01 Q0.005")
        with self.assertRaises(ValueError):
            lcnc_machine.path_mode("G1")

    def test_the_planner_is_the_installed_linuxcncs(self):
        # DEC-163: Debian's 2.9.0~pre1 runs 2.9's G64 planner; a reference of another is not
        # applicable there, the same one is
        self.assertEqual(lcnc_machine.planner_of("2.9.0~pre1+git20230208.f1270d6ed7-1+deb12u2"), 209.0)
        self.assertEqual(lcnc_machine.planner_of("1:2.10.0~pre0"), 210.0)
        self.assertEqual(lcnc_machine.planner_of("2.11.1"), 210.0)
        self.assertIsNone(lcnc_machine.planner_of("unknown"))
        # the exact planner (no look-ahead) is the 210 model whatever the version
        self.assertEqual(lcnc_machine.planner_of("2.9.0~pre1", "exact"), 210.0)
        with self.assertRaises(lcnc_machine.NotApplicable) as e:
            lcnc_machine.machine_config([], runs_planner=209.0)
        self.assertIn("nc.trajectory_planner: 209", str(e.exception))
        with self.assertRaises(lcnc_machine.NotApplicable) as e:
            lcnc_machine.machine_config([{"id": "nc.trajectory_planner", "value": 209}], runs_planner=209.0)
        self.assertIn("nc.startup_g64_p_mm: 0", str(e.exception))
        g64 = [{"id": "nc.trajectory_planner", "value": 209}, {"id": "nc.startup_g64_p_mm", "value": 0}]
        lcnc_machine.machine_config(g64, runs_planner=209.0)
        # under the exact stop the adapter runs by default, the tolerance plays no part
        lcnc_machine.machine_config(g64[:1], "G61.1", runs_planner=209.0)
        with self.assertRaises(lcnc_machine.NotApplicable) as e:
            lcnc_machine.machine_config(g64, "G64 P0.005", runs_planner=209.0)
        self.assertIn("nc.startup_g64_p_mm: 0.005", str(e.exception))

    def test_what_linuxcnc_cannot_have_is_not_applicable(self):
        for params, says in [
            ([{"id": "nc.rapid_mm_min", "axis": "Z", "value": 3000}], "slowest axis gives 3000"),
            ([{"id": "plc.fin_ms", "value": 50}], "no M function completion"),
            ([{"id": "nc.rigid_overshoot_pitches", "value": 5}], "overshoot"),
            ([{"id": "nc.g74_g84_plane_points", "value": 0}], "permuted points"),
            ([{"id": "271", "value": 1}], "no LinuxCNC setting"),
        ]:
            with self.assertRaises(lcnc_machine.NotApplicable) as e:
                lcnc_machine.machine_config(params)
            self.assertIn(says, str(e.exception))


def row(cycle, z=0.0, rpm=0.0, revs=0.0, cmd=0.0, on=0, fwd=0, rev=0, line=0, mtype=0, index=0):
    return {"n": cycle, "X": 0.0, "Y": 0.0, "Z": z, "rpm": rpm, "revs": revs, "speed_cmd": cmd,
            "clock": cycle / 1000.0, "on": on, "fwd": fwd, "rev": rev, "at_speed": 0, "index": index,
            "inpos": 1, "flood": 0, "mist": 0, "line": line, "mtype": mtype, "cycle": cycle}


def agent_arm_estop(trip, period_s):
    """The threshold the agent's arm_estop gives estop_at.in0 for an E-stop in cycle `trip`, its
    source run with a stand-in for LinuxCNC's hal module."""
    import ast

    with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "lcnc_agent.py")) as f:
        tree = ast.parse(f.read())
    fn = next(n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == "arm_estop")
    set_p = {}

    class Hal:
        @staticmethod
        def set_p(name, value):
            set_p[name] = value

    scope = {"hal": Hal}
    exec(compile(ast.Module(body=[fn], type_ignores=[]), "lcnc_agent.py", "exec"), scope)
    scope["arm_estop"](trip, period_s)
    return float(set_p["estop_at.in0"])


def power_on_mdi():
    """The agent's power-on blocks (lcnc_agent.POWER_ON_MDI), read from its source: the agent
    imports LinuxCNC's own modules."""
    import ast

    with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "lcnc_agent.py")) as f:
        src = f.read()
    for node in ast.parse(src).body:
        if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", "") == "POWER_ON_MDI":
            return [line.format(path_mode="G61.1") for line in ast.literal_eval(node.value)]
    raise AssertionError("no POWER_ON_MDI in lcnc_agent.py")


class PowerOn(unittest.TestCase):
    # A program before (a G88 with P0.3, M49) and, after the power-on blocks, a G84 without P.
    BEFORE = ["G21 G17 M3 S500 F200", "G0 X0 Y0 Z10", "G88 X5 Z-5 R2 P0.3", "G80", "M49"]
    AFTER = ["M3 S600 F600", "G0 Z5", "G84 Z-3 R2", "M2"]

    def test_power_on_clears_what_a_program_leaves_in_the_interpreter(self):
        # LinuxCNC keeps a canned cycle's P for the next cycle without P across programs, and a
        # G84 enables the overrides again only when they were on as it was read (X3: a G84 dwelt
        # 0.3 s at the bottom after cycles/g88). Oracle: LinuxCNC's own interpreter (rs274 -g).
        blocks = power_on_mdi()
        self.assertIn("M48", blocks)
        rs274 = shutil.which("rs274")
        if rs274 is None:  # without LinuxCNC: the blocks that do it are there
            self.assertTrue(any(" P0 " in f" {b} " and "G82" in b and "R0" in b for b in blocks), blocks)
            return
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "p.ngc")
            with open(path, "w") as f:
                f.write("\n".join(self.BEFORE + blocks + self.AFTER) + "\n")
            out = subprocess.run([rs274, "-g", path], capture_output=True, text=True, timeout=60,
                                 stdin=subprocess.DEVNULL).stdout
        canon = [l.split("N..... ", 1)[1] for l in out.splitlines() if "N..... " in l]
        g84 = canon[max(i for i, l in enumerate(canon) if l.startswith("STRAIGHT_TRAVERSE")):]
        self.assertIn("DWELL(0.3000)", canon)  # the G88's
        self.assertIn("DWELL(0.0000)", g84, g84)
        self.assertNotIn("DWELL(0.3000)", g84, g84)
        self.assertIn("ENABLE_FEED_OVERRIDE()", g84, g84)
        self.assertIn("ENABLE_SPEED_OVERRIDE(0)", g84, g84)


class Recording(unittest.TestCase):
    PROGRAM = "G21 M3 S500\nG0 X0 Z5\nG33.1 Z-1 K1\nM2\n"
    CFG = {"period_us": 1000, "zsp_ms": 8}

    def rows(self):
        rows = [row(c) for c in range(100, 110)]
        c = 110
        # M3 at cycle 110: on, forward, the speed ramps 6 rpm per cycle
        for k in range(5):
            rows.append(row(c + k, rpm=6.0 * (k + 1), revs=0.0001 * k, cmd=500, on=1, fwd=1))
        # the rapid (line 2) from 115
        for k in range(5):
            rows.append(row(115 + k, z=0.5 * (k + 1), rpm=30, revs=0.1, cmd=500, on=1, fwd=1, line=2, mtype=1))
        # the index is armed at 120 (G33.1 begins), the tap runs from 122, the spindle reverses at 125
        rows.append(row(120, z=2.5, rpm=30, revs=0.2, cmd=500, on=1, fwd=1, index=1))
        rows.append(row(121, z=2.5, rpm=30, revs=1.0, cmd=500, on=1, fwd=1))
        for k in range(3):
            rows.append(row(122 + k, z=2.4 - 0.1 * k, rpm=30, revs=1.1, cmd=500, on=1, fwd=1, line=3))
        for k in range(3):
            rows.append(row(125 + k, z=2.2, rpm=-30, revs=1.2, cmd=-500, on=1, rev=1, line=3))
        return rows

    def test_a_recording_becomes_trace_events(self):
        agent = {"c_run": 105, "states": [{"cycle": 109, "interp": 2, "paused": False, "task": 4}],
                 "given": [], "messages": [], "end": {"reason": "program_end", "cycle": 127, "settled": 127}}
        tr = lcnc_trace.Trace(self.PROGRAM, self.rows(), agent, self.CFG, 1000)
        self.assertEqual(tr.t0, 110)
        ev = tr.build()
        text = [lcnc_trace.dumps(e) for e in ev]
        samples = [e for e in ev if e["kind"] == "sample"]
        # the sample at 0 is the state before M3; at 1 ms the first step of the ramp
        self.assertEqual(lcnc_trace.dumps(samples[0]["spindle"]), '{"rpm":0,"angle_deg":0}')
        self.assertEqual(lcnc_trace.dumps(samples[1]["spindle"]), '{"rpm":6,"angle_deg":0}')
        self.assertIn('{"t_us":0,"kind":"block","line":1,"text":"G21 M3 S500"}', text)
        self.assertIn('{"t_us":0,"kind":"function","letter":"S","code":500}', text)
        self.assertIn('{"t_us":0,"kind":"function","letter":"M","code":3}', text)
        self.assertIn('{"t_us":5000,"kind":"block","line":2,"text":"G0 X0 Z5"}', text)
        # G33.1 starts when the index is armed, the retract when the spindle turns backwards
        self.assertIn('{"t_us":10000,"kind":"block","line":3,"text":"G33.1 Z-1 K1"}', text)
        self.assertIn('{"t_us":10000,"kind":"phase","name":"cutting"}', text)
        self.assertIn('{"t_us":15000,"kind":"phase","name":"retract"}', text)
        self.assertNotIn("M4", " ".join(t for t in text if '"function"' in t))
        self.assertEqual(ev[-1]["kind"], "end")
        times = [e["t_us"] for e in ev]
        self.assertEqual(times, sorted(times))

    def test_g331s_sense_restored_as_the_tap_passes_the_start_is_its_m3(self):
        # R2 (g331/standard, after_m3): on the way out LinuxCNC gives the spindle its sense again
        # as the tap passes the start (tp.c FINAL_REVERSAL), still in the G33.1 line: that is the
        # M3 (the reference gives it there, DEC-149), not the line's end
        rows = self.rows()
        for k in range(4):
            rows.append(row(128 + k, z=2.3 + 0.05 * k, rpm=-30 + 20 * k, revs=1.1, cmd=500, on=1, fwd=1, line=3))
        rows += [row(132 + k, z=2.5, rpm=30, revs=1.2, cmd=500, on=1, fwd=1, line=4) for k in range(3)]
        agent = {"c_run": 105, "states": [{"cycle": 109, "interp": 2, "paused": False, "task": 4}],
                 "given": [], "messages": [], "end": {"reason": "program_end", "cycle": 134, "settled": 134}}
        ev = lcnc_trace.Trace(self.PROGRAM, rows, agent, self.CFG, 1000).build()
        m = [(e["t_us"], e["code"]) for e in ev if e["kind"] == "function" and e["letter"] == "M"]
        self.assertEqual([x for x in m if x[1] == 3], [(0, 3), (18000, 3)])

    def test_a_single_block_step_ends_its_cycles_phases(self):
        # I4: LinuxCNC's step through the G33.1 line stands done back at the start (the task took
        # up the next line): the reference's block is over there (phase idle with SPL), while
        # LinuxCNC's next line starts only after the cycle start
        rows = self.rows()
        for k in range(4):
            rows.append(row(128 + k, z=2.3 + 0.05 * k, rpm=-30 + 20 * k, revs=1.1, cmd=500, on=1, fwd=1, line=3))
        rows += [row(132 + k, z=2.5, rpm=30, revs=1.2, cmd=500, on=1, fwd=1, line=3) for k in range(10)]
        agent = {"c_run": 105, "given": [], "messages": [],
                 "states": [{"cycle": 109, "interp": 2, "paused": False, "task": 4},
                            {"cycle": 135, "interp": 4, "paused": True, "task": 4, "step": True}],
                 "end": {"reason": "stopped", "cycle": 141}}
        ev = lcnc_trace.Trace(self.PROGRAM, rows, agent, self.CFG, 1000).build()
        phases = [(e["t_us"], e["name"]) for e in ev if e["kind"] == "phase"]
        spl = [e["t_us"] for e in ev if e["kind"] == "signal" and e["name"] == "SPL" and e["value"] == 1]
        self.assertEqual(spl, [25000])
        self.assertEqual(phases[-1], (25000, "idle"))
        # a feed hold's standstill (no step) leaves the phase as it was
        agent["states"][1].pop("step")
        ev = lcnc_trace.Trace(self.PROGRAM, rows, agent, self.CFG, 1000).build()
        self.assertEqual([e["name"] for e in ev if e["kind"] == "phase"][-1], "retract")

    def test_a_pause_is_reported_where_the_axes_stand_still(self):
        # the task reports paused at cycle 114 while the rapid still moves until 116
        rows = [row(c) for c in range(100, 110)]
        for k, z in enumerate([0.5, 1.0, 1.5, 2.0, 2.4, 2.6, 2.7, 2.7, 2.7, 2.7, 2.7, 2.7]):
            rows.append(row(110 + k, z=z, rpm=30, cmd=500, on=1, fwd=1, line=2, mtype=1))
        agent = {"c_run": 105, "given": [], "messages": [],
                 "states": [{"cycle": 109, "interp": 2, "paused": False, "task": 4},
                            {"cycle": 114, "interp": 2, "paused": True, "task": 4}],
                 "end": {"reason": "time_limit", "cycle": 121, "settled": 121}}
        ev = lcnc_trace.Trace("G21 M3 S500\nG0 Z5\nM2\n", rows, agent, self.CFG, 1000).build()
        spl = [e["t_us"] for e in ev if e["kind"] == "signal" and e["name"] == "SPL" and e["value"] == 1]
        # not at the paused report (cycle 114, 4 ms) but at cycle 117, the first without motion
        self.assertEqual(spl, [7000])

    def test_a_hold_is_reported_when_motion_went_on_before_the_cycle_start_was_stamped(self):
        # cycles/g81_feed_hold (adapter17-6): Z stood from cycle 11733 to the cycle start, and
        # moved again in the very cycle the agent stamped the cycle start taken: still a hold
        rows = [row(c, z=2.0) for c in range(100, 110)]
        for k, z in enumerate([1.99, 1.98, 1.975, 1.972, 1.971] + [1.97] * 10 + [1.969, 1.968]):
            rows.append(row(110 + k, z=z, rpm=30, cmd=500, on=1, fwd=1, line=2, mtype=2))
        agent = held(112, "cycle_start", (125, 121, 122), 126)
        agent["states"][-1]["cycle"] = 125  # the task resumed in the cycle it took the start
        ev = lcnc_trace.Trace("G21 M3 S500\nG1 Z-5 F60\nM2\n", rows, agent, self.CFG, 1000).build()
        spl = [(e["t_us"], e["value"]) for e in ev if e["kind"] == "signal" and e["name"] == "SPL"]
        self.assertEqual(spl, [(6000, 1), (15000, 0)])

    def test_a_pause_in_a_synchronised_move_is_reported_where_motion_holds(self):
        # I1: feed hold during a G33.1 at cycle 117: LinuxCNC runs the tap to its end (tp.c pauses
        # unsynchronised segments only); the tap stands still at its reversal (121-123) and holds
        # once back at the start (from 129); the cycle start is taken at 140
        rows = [row(c) for c in range(100, 110)]
        rows += [row(c, rpm=30, cmd=500, on=1, fwd=1) for c in range(110, 115)]
        z = [5 - 0.1 * k for k in range(6)] + [4.5] * 3 + [4.5 + 0.1 * k for k in range(1, 6)] + [5.0] * 16
        rows += [row(115 + k, z=v, rpm=30, cmd=500, on=1, fwd=1, line=3) for k, v in enumerate(z)]
        agent = held(117, "cycle_start", (140, 139, 140), 144)
        ev = lcnc_trace.Trace("G21 M3 S500\nG0 X0 Z5\nG33.1 Z-1 K1\nG0 Z20\nM2\n", rows, agent, self.CFG,
                              1000).build()
        spl = [(e["t_us"], e["value"]) for e in ev if e["kind"] == "signal" and e["name"] == "SPL"]
        # not at the reversal (121, 11 ms) but where the tap stands back at the start (129)
        self.assertEqual(spl, [(19000, 1), (30000, 0)])
        # a run held with nothing to release it ends where the hold took effect
        agent = dict(agent, given=agent["given"][:1], states=agent["states"][:2],
                     end={"reason": "stopped", "cycle": 144})
        tr = lcnc_trace.Trace("G21 M3 S500\nG0 X0 Z5\nG33.1 Z-1 K1\nG0 Z20\nM2\n", rows, agent, self.CFG, 1000)
        ev = tr.build()
        self.assertEqual(ev[-1]["t_us"], 19000)
        self.assertIn({"t_us": 19000, "kind": "signal", "name": "SPL", "value": 1}, ev)

    def test_the_line_before_an_armed_move_is_not_entered_again(self):
        ev = lcnc_trace.Trace(self.PROGRAM, self.rows_line_lagging(), self.AGENT, self.CFG, 1000).build()
        blocks = [e["line"] for e in ev if e["kind"] == "block"]
        self.assertEqual(blocks, sorted(blocks), blocks)

    AGENT = {"c_run": 105, "states": [{"cycle": 109, "interp": 2, "paused": False, "task": 4}],
             "given": [], "messages": [], "end": {"reason": "program_end", "cycle": 127, "settled": 127}}

    def rows_line_lagging(self):
        # motion still names line 2 for a period after the index is armed for line 3
        rows = self.rows()
        for r in rows:
            if r["cycle"] == 121:
                r["line"] = 2
        return rows

    def test_motions_line_and_type_are_read_with_the_positions_they_belong_to(self):
        # Q1: motion writes motion.program-line and motion.motion-type from the cycle before
        # (control.c output_to_hal before update_status): in the recording the G76's retract (a
        # traverse, line 4) shows one period after X left 9.2, and the retract was stamped there
        def rec(c, x, line, mtype):
            r = row(c, line=line, mtype=mtype)
            r["X"] = x
            return " ".join(str(r[k]) for k in lcnc_trace.COLUMNS)

        text = [rec(100, 9.2, 3, 2), rec(101, 9.2, 3, 2), rec(102, 9.201953, 3, 2), rec(103, 9.21, 4, 1),
                rec(104, 9.23, 4, 1), "overrun", rec(106, 9.25, 4, 1)]
        with tempfile.NamedTemporaryFile("w", suffix=".txt", delete=False) as f:
            f.write("\n".join(text) + "\n")
        try:
            rows = lcnc_trace.read_rows(f.name, 1000)
        finally:
            os.unlink(f.name)
        self.assertEqual([(r["cycle"], r["line"], r["mtype"]) for r in rows],
                         [(100, 3, 2), (101, 3, 2), (102, 4, 1), (103, 4, 1), (104, 4, 1), (106, 4, 1)])

    def test_a_subroutines_body_runs_after_its_call(self):
        # X2 (lex/sub_while_arc_as_rs274): LinuxCNC's motion names the sub's body line (3) for
        # the call's feed; the call (line 11) ran before it, the arc (line 12) comes 1.129 s later
        prog = ("%\no100 sub\n  g1 x[#1] y[#2] f[#3 * 2]\no100 endsub\nN10 g17 g21 g90 g94\n/#<depth> = -2\n#5 = 3\n"
                "o200 while [#5 GT 1]\n  #5 = [#5 - 1]\no200 endwhile\no100 call [10] [#5 * 5] [300]\n"
                "G2 X20 Y5 I5 J0 (arc)\ng0 z[#<depth>]\nM2\n%\n")
        rows = [row(c) for c in range(100, 110)]
        rows += [row(110 + k, z=0.0, line=3, mtype=2) for k in range(5)]
        for r in rows[-5:]:
            r["X"] = 0.01 * (r["cycle"] - 109)
        rows += [row(115 + k, line=12, mtype=2) for k in range(3)]
        for r in rows[-3:]:
            r["X"], r["Y"] = 10.0 + 0.01 * (r["cycle"] - 114), 5.0
        agent = dict(self.AGENT, end={"reason": "program_end", "cycle": 117, "settled": 117})
        ev = lcnc_trace.Trace(prog, rows, agent, self.CFG, 1000).build()
        blocks = {e["line"]: e["t_us"] for e in ev if e["kind"] == "block"}
        self.assertEqual(blocks[11], 0)  # the call, with its feed
        self.assertEqual(blocks[3], 0)
        self.assertEqual(blocks[12], 5000)
        self.assertEqual([e["line"] for e in ev if e["kind"] == "block"].count(3), 1)

    def test_g76s_retract_begins_with_x(self):
        # Q1 / I1: the pass's last servo period already shows the traverse's motion type while
        # only Z ends its cut; the retract is where X leaves the thread's depth
        prog = "G18 G21 M3 S600\nG0 X7 Z3\nG76 P1.5 Z-20 I-1 J0.5 K0.92\nM2\n"

        def phases(x_at_115):
            rows = [row(c) for c in range(100, 110)]
            rows += [row(110 + k, z=3 - 0.1 * k, line=3, mtype=2) for k in range(5)]
            rows += [row(115 + k, z=2.599, line=3, mtype=1) for k in range(10)]
            for r in rows[10:]:
                r["X"] = 5.5
            for r in rows[15:]:
                r["X"] += x_at_115 * (r["cycle"] - 114)
            agent = dict(self.AGENT, end={"reason": "time_limit", "cycle": 124, "limit_cycles": 14})
            ev = lcnc_trace.Trace(prog, rows, agent, self.CFG, 1000).build()
            return [(e["t_us"], e["name"]) for e in ev if e["kind"] == "phase"]

        # held after the pass: X stands, the phase stays cutting
        self.assertEqual(phases(0.0)[-1], (0, "cutting"))
        # the rapid out: retract from the first period X moves
        self.assertEqual(phases(0.0001)[-1], (5000, "retract"))
        # the infeed's last period already shows the feed's type: the pass has not cut yet
        rows = [row(c) for c in range(100, 110)]
        rows += [row(110, line=3, mtype=2), row(111, line=3, mtype=2)] + [
            row(112 + k, z=-0.1 * (k + 1), line=3, mtype=2) for k in range(5)]
        for r, x in zip(rows[10:], [5.6, 5.5] + [5.5] * 5):
            r["X"] = x
        agent = dict(self.AGENT, end={"reason": "time_limit", "cycle": 116, "limit_cycles": 6})
        ev = lcnc_trace.Trace(prog, rows, agent, self.CFG, 1000).build()
        self.assertEqual([e["name"] for e in ev if e["kind"] == "phase"], ["positioning", "cutting"])

    def test_a_permuted_tap_in_g19_has_the_references_phases(self):
        # DEC-166 (cycles/g99_planes): LinuxCNC's G84 in G19 feeds to its permuted point, X up
        # and Y down (the tool axis X goes up while it cuts); then the feed out along Y, and the
        # next hole's traverse: cutting from the feed's first period, retract at the bottom's
        # standstill, positioning with the traverse, as the reference marks them
        prog = "G19 G21 M3 S500 F200\nG0 X20 Y0 Z0\nG84 Y10 Z15 X-5 R5 L2\nM2\n"
        pts = [(20, 0, 0), (20, 10, 15), (5, 10, 15)]  # traverses to the hole and down to R
        cut = [(5 + k, 10 - 1.5 * k, 15 - 0.5 * k) for k in range(1, 11)]  # to (15, -5, 10)
        out = [(15, -5 + k, 10) for k in range(1, 11)]  # the feed out to (15, 5, 10)
        rows = [row(c) for c in range(100, 110)]
        c = 110
        for pts_, mtype in ((pts, 1), (cut, 2), ([cut[-1]] * 5, 2), (out, 2), ([(20, 5, 10)], 1)):
            for x, y, z in pts_:
                r = row(c, z=z, line=3, mtype=mtype, rpm=500, cmd=500, on=1, fwd=1)
                r["X"], r["Y"] = x, y
                rows.append(r)
                c += 1
        agent = dict(self.AGENT, end={"reason": "time_limit", "cycle": c - 1, "limit_cycles": c - 111})
        ev = lcnc_trace.Trace(prog, rows, agent, self.CFG, 1000).build()
        got = [(e["t_us"] // 1000, e["name"]) for e in ev if e["kind"] == "phase"]
        self.assertEqual([n for _, n in got], ["positioning", "cutting", "retract", "positioning"], got)
        self.assertEqual(got[1][0], 3)  # the first feed period
        self.assertEqual(got[2][0], 13)  # the first still period at the bottom

    def test_a_feed_hold_in_a_drilling_cycle_is_not_its_bottom(self):
        # I1 (cycles/g81_feed_hold): held in the feed in, the drill stands; G81 (no dwell) goes to
        # its retract only when it stands at the bottom, not in a hold
        rows = [row(c) for c in range(100, 110)]
        rows += [row(110 + k, z=2 - 0.01 * k, rpm=800, cmd=800, on=1, fwd=1, line=3, mtype=2) for k in range(8)]
        rows += [row(118 + k, z=1.93, rpm=800, cmd=800, on=1, fwd=1, line=3, mtype=2) for k in range(12)]
        agent = {"c_run": 105, "messages": [], "given": [{"cycle": 115, "sent": 114, "due": 115,
                                                          "input": {"name": "feed_hold"}}],
                 "states": [{"cycle": 109, "interp": 2, "paused": False, "task": 4},
                            {"cycle": 115, "interp": 3, "paused": True, "task": 4}],
                 "end": {"reason": "stopped", "cycle": 129}}
        prog = "G17 G21 M3 S800 F300\nG0 X0 Y0 Z10\nG81 X10 Z-10 R2\nG80 M2\n"
        ev = lcnc_trace.Trace(prog, rows, agent, self.CFG, 1000).build()
        self.assertEqual([e["name"] for e in ev if e["kind"] == "phase"][-1], "cutting")
        self.assertIn({"t_us": 8000, "kind": "signal", "name": "SPL", "value": 1}, ev)
        # the cycle start taken at 126, the feed goes on from 128: cutting throughout
        rows += [row(130 + k, z=1.93 - 0.01 * (k - 1) if k > 1 else 1.93, rpm=800, cmd=800, on=1, fwd=1, line=3,
                     mtype=2) for k in range(6)]
        agent = dict(agent, given=agent["given"] + [{"cycle": 126, "sent": 125, "due": 126,
                                                     "input": {"name": "cycle_start"}}],
                     states=agent["states"] + [{"cycle": 127, "interp": 2, "paused": False, "task": 4}],
                     end={"reason": "time_limit", "cycle": 135, "limit_cycles": 25})
        ev = lcnc_trace.Trace(prog, rows, agent, self.CFG, 1000).build()
        self.assertEqual([e["name"] for e in ev if e["kind"] == "phase"], ["positioning", "cutting"])

    def test_g88s_program_stop_ends_its_dwell(self):
        # A1 (cycles/g88): the program stop after G88's dwell and spindle stop is reported by the
        # task (paused) in the servo cycle the trace's dwell count ends or before it: the dwell is
        # over (G88 stops the spindle only after it), the tool at the bottom in the retract phase
        # (the scenario's `when: {phase: retract}` gives the cycle start from there)
        prog = "G17 G21 M3 S500 F200\nG0 X5 Y0 Z2\nG88 X5 Z-5 R2 P0.01\nG80 M2\n"

        def phases(pause_at):
            rows = [row(c) for c in range(100, 110)]
            rows += [row(110 + k, z=2 - 0.5 * (k + 1), rpm=500, cmd=500, on=1, fwd=1, line=3, mtype=2)
                     for k in range(14)]
            rows += [row(124 + k, z=-5.0, rpm=500, cmd=500, on=1, fwd=1, line=3, mtype=2) for k in range(8)]
            rows += [row(132 + k, z=-5.0, line=3, mtype=2) for k in range(10)]  # M5, then the stop
            for r in rows:
                r["X"] = 5.0
            agent = {"c_run": 105, "messages": [], "given": [],
                     "states": [{"cycle": 109, "interp": 2, "paused": False, "task": 4},
                                {"cycle": pause_at, "interp": 3, "paused": True, "task": 4}],
                     "end": {"reason": "stopped", "cycle": 141}}
            ev = lcnc_trace.Trace(prog, rows, agent, self.CFG, 1000).build()
            return [e["name"] for e in ev if e["kind"] == "phase"]

        for pause_at in (132, 133, 134):
            with self.subTest(pause_at=pause_at):
                self.assertEqual(phases(pause_at)[-3:], ["cutting", "dwell", "retract"])

    def test_a_stalled_spindle_started_stays_at_zero_speed(self):
        # T2 (g84/spindle_never_at_speed): stalled from the start, M3 turns nothing: ZSP stays 1
        # (the reference's drive); a spindle that turns drops it with its start
        def zsp(rpm):
            rows = [row(c) for c in range(100, 110)]
            rows += [row(110 + k, z=0.1 * (k + 1), line=2, mtype=1) for k in range(5)]
            rows += [row(115 + k, z=0.5, rpm=rpm, cmd=600, on=1, fwd=1, line=3) for k in range(20)]
            agent = dict(self.AGENT, end={"reason": "time_limit", "cycle": 134, "limit_cycles": 24})
            ev = lcnc_trace.Trace("G21\nG0 Z0.5\nM3 S600\nM2\n", rows, agent, self.CFG, 1000).build()
            return [(e["t_us"], e["value"]) for e in ev if e["kind"] == "signal" and e["name"] == "ZSP"]

        self.assertEqual(zsp(0.0), [(0, 1)])
        self.assertEqual(zsp(6.0), [(0, 1), (5000, 0)])

    def test_a_direct_reversal_after_a_cycle_is_the_next_lines_m4(self):
        # g84/single_block: `G80 M4` after the G84 line turns the spindle from forward to reverse
        # in one servo period (canon START_SPINDLE_COUNTERCLOCKWISE alone), while motion still
        # names the G84 line: the M4 of line 4, not the cycle's M5 + M4 (its reversals pass
        # through a period at rest)
        prog = "G17 G21 G98 M3 S600 F600\nG0 X0 Y0 Z10\nG84 X20 Z-10 R2 P0.2\nG80 M4\nG0 Z20\nM2\n"
        rows = [row(c) for c in range(100, 110)]
        rows += [row(110 + k, z=10 - 0.1 * k, rpm=600, cmd=600, on=1, fwd=1, line=3, mtype=2) for k in range(5)]
        rows += [row(115 + k, z=9.6, rpm=600 - 50 * k, cmd=-600, on=1, rev=1, line=3) for k in range(3)]
        rows += [row(118 + k, z=9.6 + 0.1 * (k + 1), rpm=-500, cmd=-600, on=1, rev=1, line=5, mtype=1)
                 for k in range(5)]
        agent = {"c_run": 105, "states": [{"cycle": 109, "interp": 2, "paused": False, "task": 4}],
                 "given": [], "messages": [], "end": {"reason": "time_limit", "cycle": 122, "settled": 122}}
        ev = lcnc_trace.Trace(prog, rows, agent, self.CFG, 1000).build()
        m = [(e["t_us"], e["code"]) for e in ev if e["kind"] == "function" and e["letter"] == "M"]
        self.assertEqual([x for x in m if x[0] > 0], [(5000, 4)])
        self.assertIn({"t_us": 5000, "kind": "block", "line": 4, "text": "G80 M4"}, ev)

    def test_motion_stopping_after_a_reset_is_the_abort(self):
        # I2 / I1 (cycles/g81_reset, g331/feed_hold_then_reset_mid_stroke): the reset is sent at
        # 118 (a feed hold was pending since 112), motion stops at 121, the spindle goes off at
        # 125 (where the reset is stamped): no retract phase, no hold taking effect
        prog = "G17 G21 G98 M3 S800 F300\nG0 X0 Y0 Z10\nG81 X10 Z-10 R2\nG80 M2\n"
        rows = [row(c) for c in range(100, 110)]
        z = [2 - 0.005 * k for k in range(11)] + [1.95 - 0.002, 1.95 - 0.003] + [1.947] * 17
        rows += [row(110 + k, z=v, rpm=800, cmd=800, on=1 if 110 + k < 125 else 0, fwd=1, line=3, mtype=2)
                 for k, v in enumerate(z)]
        agent = held(112, "reset", (140, 118, 119), 140, end_reason="reset")
        ev = lcnc_trace.Trace(prog, rows, agent, self.CFG, 1000).build()
        self.assertEqual([e["name"] for e in ev if e["kind"] == "phase"][-1], "cutting")
        self.assertFalse([e for e in ev if e["kind"] == "signal" and e["name"] == "SPL" and e["value"]])
        self.assertEqual((ev[-1]["kind"], ev[-1]["t_us"]), ("end", 15000))

    def test_exact_decimals(self):
        for x, digits, want in [(0.000001, 6, "0.000001"), (-12.5, 6, "-12.5"), (50.0, 6, "50"),
                                (-0.0000004, 6, "0"), (359.9996, 3, "360"), (2.999994, 6, "2.999994")]:
            self.assertEqual(lcnc_trace.dec(x, digits), want)

    def test_interpreter_codes(self):
        self.assertEqual(lcnc_trace.alarm_code("R less than z in cycle in xy plane"), "NC-1092")
        self.assertEqual(lcnc_trace.alarm_code("Cannot feed with zero feed rate"), "NC-1091")
        self.assertEqual(lcnc_trace.alarm_code("K word missing with g33/g33.1"), "NC-1096")
        self.assertEqual(lcnc_trace.alarm_code("Spindle not turning in g88"), "NC-1095")


class Leads(unittest.TestCase):
    class Args:
        log = None
        keep = None
        max_run_s = 120

    def adapter(self, lates):
        """An adapter whose LinuxCNC runs answer with these input timings in turn (late_us)."""
        a = lcnc_adapter.Adapter(self.Args())
        a.sc = lcnc_adapter.Scenario({}, {"period_us": 1000})
        runs = []

        def run_once():
            late = lates[len(runs)]
            runs.append(dict(a.leads))
            a.leads["reset"] = 24000  # the task took the reset 24 ms after it was sent
            return {"events": [], "inputs": [{"input": "reset", "late_us": late}]}

        a.run_once = run_once
        return a, runs

    def test_an_input_late_by_its_unknown_latency_is_given_again_earlier(self):
        # I2: cycles/g81_reset's reset acted 24 ms after its time, the first reset of the session
        a, runs = self.adapter([24000, 1000])
        a.run()
        self.assertEqual(runs, [{}, {"reset": 24000}])  # run again with the measured lead
        # with the lead known, one run; on time, one run
        a, runs = self.adapter([24000])
        a.leads["reset"] = 20000
        a.run()
        self.assertEqual(len(runs), 1)
        a, runs = self.adapter([1000])
        a.run()
        self.assertEqual(len(runs), 1)


    def test_an_outlier_lead_is_measured_once_more(self):
        # A3 (g76/spindle_override): the session's first spindle override taken 82 ms after it
        # was sent, given 80 ms early with that lead the next run (taken 2 ms after sent): run a
        # third time with the 2 ms; a lead measured right the first time runs twice
        def adapter(runs_said):
            a = lcnc_adapter.Adapter(self.Args())
            a.sc = lcnc_adapter.Scenario({}, {"period_us": 1000})
            seen = []

            def run_once():
                late, lead = runs_said[len(seen)]
                seen.append(dict(a.leads))
                a.leads["spindle_override"] = lead
                return {"events": [], "inputs": [{"input": "spindle_override", "late_us": late}]}

            a.run_once = run_once
            a.run()
            return seen

        self.assertEqual(adapter([(82000, 82000), (-80000, 2000), (0, 2000)]),
                         [{}, {"spindle_override": 82000}, {"spindle_override": 2000}])
        self.assertEqual(len(adapter([(24000, 24000), (1000, 24000)])), 2)

    def test_a_late_time_0_runs_again(self):
        # under load the agent's time 0 (the inputs count from it) came 50 ms after the trace's
        a = lcnc_adapter.Adapter(self.Args())
        a.sc = lcnc_adapter.Scenario({}, {"period_us": 1000})
        said = iter([50000, 0])
        calls = []

        def run_once():
            calls.append(1)
            return {"events": [], "inputs": [], "t0_late_us": next(said)}

        a.run_once = run_once
        self.assertEqual(a.run()["t0_late_us"], 0)
        self.assertEqual(len(calls), 2)

    def test_a_cycle_start_teaches_no_lead(self):
        # a resume is taken only once held: a cycle start taken 21 ms after it was sent waited
        # for the hold; given 21 ms early the next time it would come before the hold, lost
        def given(name, sent, cycle, **kw):
            return dict({"input": {"name": name}, "sent": sent, "cycle": cycle}, **kw)

        self.assertIsNone(lcnc_adapter.measured_lead(given("cycle_start", 100, 121), 1000))
        self.assertEqual(lcnc_adapter.measured_lead(given("feed_override", 100, 120), 1000), 20000)
        self.assertIsNone(lcnc_adapter.measured_lead(given("reset", 100, 135), 1000))
        self.assertEqual(lcnc_adapter.measured_lead(given("reset", 100, 135, acted=True), 1000), 35000)


class Delivery(unittest.TestCase):
    def test_the_trace_is_the_last_run_whole(self):
        # I1 (cycles/g81_feed_hold): the first run with the feed hold held at Z -3.085, the run
        # with the cycle start too at Z -3.07 (the hold taken 3 ms earlier); the harness reads
        # the last run only, not the first run's events up to the stop and the last one's after
        def sample(t, z):
            return {"t_us": t, "kind": "sample", "axes": {"Z": lcnc_trace.Raw(lcnc_trace.dec(z, 6))}}

        def events(z_held, resumed):
            ev = [sample(0, 0.0), sample(1000, z_held), {"t_us": 1000, "kind": "signal", "name": "SPL", "value": 1},
                  sample(2000, z_held)]
            if resumed:
                ev += [{"t_us": 2000, "kind": "input", "name": "cycle_start", "value": ""}, sample(3000, -10.0)]
            return ev + [{"t_us": 3000, "kind": "end", "reason": "program_end"}]

        a = lcnc_adapter.Adapter(Leads.Args())
        a.sc = lcnc_adapter.Scenario({}, {"period_us": 1000})
        runs = iter([events(-3.085, False), events(-3.07, True)])
        a.run = lambda: {"events": next(runs)}
        stop = {"signal": "SPL", "value": 1}
        got = []
        ans = a.advance({"until_us": 10000, "stop_on": [stop]})
        self.assertEqual((ans["stopped_on"], ans["now_us"]), (0, 1000))
        got += json.loads(a.read({}))["events"]
        a.input({"t_us": 2000, "input": {"name": "cycle_start"}})
        while True:
            ans = a.advance({"until_us": 10000, "stop_on": []})
            got += json.loads(a.read({}))["events"]
            if ans["ended"]:
                break
        zs = [e["axes"]["Z"] for e in got if e["kind"] == "sample"]
        self.assertEqual(zs, [0, -3.07, -3.07, -10])
        self.assertEqual(got[-1]["kind"], "end")


class Conditions(unittest.TestCase):
    def test_an_onset_moved_in_a_run_again_is_not_the_next_occurrence(self):
        # g331/single_block on LinuxCNC's axis_mm machine: the second single-block stop at 330 ms
        # in the run that found it, at 331 ms in the run again with its cycle start; that 331 ms
        # was taken for the third stop, and the third cycle start given 1 ms after the second's
        # was lost. The third is the run's third onset, at 4439 ms.
        def spl(t, v):
            return {"t_us": t, "kind": "signal", "name": "SPL", "value": v}

        def events(second, third):
            ev = [spl(3000, 1), spl(101000, 0), spl(second, 1)]
            if third:
                ev += [spl(430000, 0), spl(third, 1)]
            return ev + [{"t_us": (third or second) + 1000, "kind": "end", "reason": "stopped"}]

        a = lcnc_adapter.Adapter(Leads.Args())
        a.sc = lcnc_adapter.Scenario({}, {"period_us": 1000})
        runs = iter([events(330000, None), events(331000, 4439000)])
        a.run = lambda: {"events": next(runs)}
        stop = {"signal": "SPL", "value": 1}
        ans = a.advance({"until_us": 10_000_000, "stop_on": [stop]})
        self.assertEqual((ans["stopped_on"], ans["now_us"]), (0, 3000))
        ans = a.advance({"until_us": 10_000_000, "stop_on": [stop]})
        self.assertEqual((ans["stopped_on"], ans["now_us"]), (0, 330000))
        a.input({"t_us": 430000, "input": {"name": "cycle_start"}})
        ans = a.advance({"until_us": 10_000_000, "stop_on": [stop]})
        self.assertEqual((ans["stopped_on"], ans["now_us"]), (0, 4439000))

    def test_an_axis_crossing_stops_at_its_interpolated_us(self):
        tr = lcnc_adapter.Tracker({"axis": "Z", "below": -1.5})
        s = lambda t, z: {"t_us": t, "kind": "sample", "axes": {"Z": lcnc_trace.Raw(lcnc_trace.dec(z, 6))}}
        self.assertIsNone(tr.see(s(0, 0)))
        self.assertIsNone(tr.see(s(1000, -1)))
        self.assertEqual(tr.see(s(2000, -2)), 1500)

    def test_signals_phases_blocks_functions(self):
        ev = {"t_us": 7, "kind": "signal", "name": "SPL", "value": 1}
        self.assertEqual(lcnc_adapter.Tracker({"signal": "SPL", "value": 1}).see(ev), 7)
        self.assertIsNone(lcnc_adapter.Tracker({"signal": "SPL", "value": 0}).see(ev))
        self.assertEqual(lcnc_adapter.Tracker({"phase": "cutting"}).see({"t_us": 3, "kind": "phase", "name": "cutting"}), 3)
        self.assertEqual(lcnc_adapter.Tracker({"block": 4}).see({"t_us": 5, "kind": "block", "line": 4, "text": ""}), 5)
        f = {"t_us": 9, "kind": "function", "letter": "M", "code": 3}
        self.assertEqual(lcnc_adapter.Tracker({"function": "M3"}).see(f), 9)


class SingleBlock(unittest.TestCase):
    """When a LinuxCNC step stands done. Oracle: LinuxCNC 2.9's own status while stepping
    g331/single_block's program with AUTO_STEP (interp, exec state, motion queue, in position,
    the task's current line; a row per change, at its ms)."""

    # the second step (line 1: M3 S500) given at 444 ms, at line 0; the third (line 2: G0 Z5) at
    # 866 ms, at line 2; the fourth (G33.1, with its index wait and reversal) at 1470 ms, at line 3
    STEPS = [
        (444, 0, [(445, 4, 5, 0, 1, 2)]),
        (866, 2, [(867, 4, 7, 1, 0, 3), (1047, 4, 7, 0, 1, 3)]),
        (1470, 3, [(1472, 4, 5, 1, 0, 4), (5443, 4, 5, 0, 1, 4)]),
    ]

    class St:
        def __init__(self, interp, exec_state, queue, inpos, line):
            self.interp_state, self.exec_state, self.queue, self.inpos, self.current_line = (
                interp, exec_state, queue, inpos, line)

    def held_from(self, stepper, rows, until):
        """The first ms the stepper reports the step done, polling every ms through the rows."""
        k, cur = 0, None
        for ms in range(rows[0][0], until):
            while k < len(rows) and rows[k][0] <= ms:
                cur = self.St(*rows[k][1:])
                k += 1
            if stepper.done(cur, ms):
                return ms
        return None

    def test_a_step_is_done_when_its_line_is_and_the_task_took_up_the_next(self):
        for given, line, rows in self.STEPS:
            st = lcnc_step.Stepper()
            st.step(line)
            # before LinuxCNC took the step: the line it stood at, motion at rest: not done
            self.assertFalse(st.done(self.St(4, 5, 0, 1, line), given))
            at = self.held_from(st, rows, rows[-1][0] + 10)
            self.assertEqual(at, rows[-1][0] + st.settle, (given, rows))
            self.assertTrue(st.done(self.St(4, 5, 0, 1, line + 1), at + 100))  # stays held

    def test_a_wait_inside_the_line_is_not_a_step_done(self):
        st = lcnc_step.Stepper()
        st.step(3)
        # G84's spindle reversal waits for motion with its queue empty, on the step's own line
        self.assertIsNone(self.held_from(st, [(0, 4, 7, 0, 1, 3)], 200))
        # a dwell (G84 P) on the next line's cycle stands still with the queue empty
        self.assertIsNone(self.held_from(st, [(0, 4, 8, 0, 1, 4)], 200))
        # the empty queue seen for less than the settling time, then motion again
        self.assertIsNone(self.held_from(st, [(0, 4, 7, 0, 1, 4), (2, 4, 7, 1, 0, 4)], 200))

    def test_the_start_is_stepped_again_only_for_a_first_line_that_acts(self):
        # the single-block start is stepped once more when line 1 should have changed an output
        # and none changed (the scenarios' first lines: M3 S500, M3 S600 F600)
        P = lcnc_trace.Program
        self.assertTrue(P("G21 M3 S500\nG0 X0 Z5\nM2\n").first_line_acts())
        self.assertTrue(P("(tap)\n\nG17 G21 G98 M3 S600 F600\nM2\n").first_line_acts())
        self.assertTrue(P("G0 X10\nM2\n").first_line_acts())
        self.assertFalse(P("G21 G90 S500\nM3\nM2\n").first_line_acts())
        self.assertFalse(P("G18 G21 F100\nG0 X1\n").first_line_acts())

    def test_the_program_end_is_a_step_done(self):
        st = lcnc_step.Stepper()
        st.step(4)
        self.assertEqual(self.held_from(st, [(0, 4, 3, 0, 1, 4), (5, 1, 2, 0, 1, 4)], 50), 5 + st.settle)


if __name__ == "__main__":
    unittest.main()
