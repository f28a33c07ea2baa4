"""A LinuxCNC machine for one set of `linuxcnc` dialect parameters, and the LinuxCNC instance
that runs it.

- `machine_config(params)`: the parameters of a `load` (ids and units of docs/parameters.md,
  over the dialect's defaults) as a LinuxCNC INI file and HAL file: the mapping of
  `nc-conform params --from-ini` (harness/src/ini.rs) the other way round, or the reason why
  LinuxCNC cannot be configured like that (the scenario is then not applicable).
- `Instance`: LinuxCNC started headless (`linuxcnc -r MACHINE.ini`) as an ordinary user (uspace
  `rtapi_app` refuses root), with `lcnc_agent.py` as its DISPLAY program; the adapter talks to
  the agent over a Unix socket. One instance serves every scenario with the same configuration.

Standard library only.
"""

import fcntl
import json
import math
import os
import pwd
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))

# The linuxcnc dialect's defaults (docs/parameters.md, `linuxcnc`).
DEFAULTS = {
    "nc.rigid_overshoot_pitches": 10.0,
    "nc.period_us": 1000.0,
    "nc.rapid_mm_min": 6000.0,
    "nc.rapid_ramp_ms": 100.0,
    "nc.backlash_mm": 0.0,
    "nc.feed_max_mm_min": 6000.0,
    "nc.feed_ramp_ms": 100.0,
    "nc.feed_override_max_pct": 120.0,
    "nc.feed_override_step_pct": 1.0,
    "nc.spindle_override_min_pct": 0.0,
    "nc.spindle_override_max_pct": 100.0,
    "nc.dry_run_mm_min": 2000.0,
    "nc.spindle_max_rpm": 6000.0,
    "nc.spindle_ramp_ms": 1000.0,
    "nc.orient_ms": 500.0,
    "plc.fin_ms": 0.0,
    "plc.fin_fall_ms": 0.0,
    "plc.fin_timeout_ms": 10000.0,
    "plc.zsp_ms": 8.0,
    "nc.trajectory_planner": 210.0,
    "nc.g74_g84_plane_points": 1.0,
    "nc.startup_g64_p_mm": -1.0,
}
PER_AXIS = {"nc.rapid_mm_min", "nc.rapid_ramp_ms", "nc.backlash_mm"}
AXES = "XYZ"
# Parameters that only shape inputs LinuxCNC has no counterpart for (dry run, G87's orientation
# time, the FIN timer with M functions completing at once): any value is accepted and unused.
UNUSED = {"nc.dry_run_mm_min", "nc.orient_ms", "plc.fin_timeout_ms", "plc.fin_fall_ms"}
# Parameters LinuxCNC has no setting for: only the default value can be honoured.
FIXED = {
    "nc.rigid_overshoot_pitches": "LinuxCNC's G33.1 has no overshoot allowance setting",
    "nc.feed_override_step_pct": "LinuxCNC's feed override is continuous (no switch steps)",
    "plc.fin_ms": "LinuxCNC has no M function completion (FIN) handshake",
    "nc.g74_g84_plane_points": "LinuxCNC's G84/G74 in G18/G19 always feeds to its permuted points "
    "(interp_cycles.cc, DEC-166), never along the manual's tool axis",
}
# A time constant of 0 (no ramp) as an acceleration LinuxCNC accepts.
NO_RAMP_ACC = 1.0e6
# Soft limits far beyond any scenario's travel (the reference has none).
LIMIT_MM = 10000.0


class NotApplicable(Exception):
    """LinuxCNC cannot be set up (or driven) the way the scenario asks."""


def resolve(params):
    """The `load` parameters over the defaults: {id: value} with {axis: value} for per-axis ids.

    Raises NotApplicable for an unknown id or a value LinuxCNC cannot have."""
    v = {k: ({a: d for a in AXES} if k in PER_AXIS else d) for k, d in DEFAULTS.items()}
    for p in params:
        pid, axis, value = p["id"], p.get("axis"), float(p["value"])
        if pid not in DEFAULTS:
            raise NotApplicable(f"parameter {pid} has no LinuxCNC setting")
        if pid in PER_AXIS:
            for a in (axis,) if axis else AXES:
                v[pid][a] = value
        else:
            v[pid] = value
    for pid, why in FIXED.items():
        if v[pid] != DEFAULTS[pid]:
            raise NotApplicable(f"{pid} = {v[pid]:g}: {why}")
    return v


PATH_MODE = re.compile(r"^(G61\.1|G61|G64( ?P[0-9.]+)?( ?Q[0-9.]+)?)$")


def path_mode(text):
    """A power-on path mode as LinuxCNC's startup code writes it: `G61.1`, `G61`, `G64`,
    `G64 P0.005`, `G64 P0.01 Q0.005` (letters upper case, one space before P and Q)."""
    t = re.sub(r"\s+", "", text.upper())
    t = re.sub(r"([PQ])", r" \1", t)
    if not PATH_MODE.match(t):
        raise ValueError(f"not a path mode: {text!r} (G61.1, G61, G64 or G64 P<tolerance> [Q<tolerance>])")
    return t


def startup_path_mode(ini_text):
    """The path mode a machine's INI file powers on in: the last G61.1, G61 or G64 (with its P
    and Q) of [RS274NGC] RS274NGC_STARTUP_CODE, or None when it names none (LinuxCNC's own
    power-on mode is then G64, blending with no tolerance)."""
    section, code = None, None
    for raw in ini_text.splitlines():
        line = raw.strip()
        if line.startswith("[") and line.endswith("]"):
            section = line[1:-1].strip()
        elif section == "RS274NGC" and "=" in line and not line.startswith(("#", ";")):
            key, value = line.split("=", 1)
            if key.strip() == "RS274NGC_STARTUP_CODE" and code is None:
                code = value
    if code is None:
        return None
    code = re.sub(r"\([^)]*\)|;.*", " ", code.upper())
    found = None
    for m in re.finditer(r"G\s*(61\.1|61|64)(?![0-9.])((?:\s*[PQ]\s*[0-9.]+)*)", code):
        found = path_mode("G" + m.group(1) + m.group(2))
    return found


def num(x):
    """A number as INI/HAL text (no exponent, no trailing zeros)."""
    s = f"{x:.9f}".rstrip("0").rstrip(".")
    return s if s not in ("", "-0") else "0"


def planner_of(version, planner="default"):
    """The `nc.trajectory_planner` a LinuxCNC version runs with the adapter's `--planner`
    (DEC-163): with LinuxCNC's own look-ahead (`default`), 209 for 2.9 (its G64 planner halves the
    acceleration of a move no move follows and blends with its arcs; in canned cycles its corners
    lose ARC_BLEND_KINK_RATIO of the acceleration), 210 for 2.10 and later; with `exact`
    (ARC_BLEND_OPTIMIZATION_DEPTH = 1: every move ends at rest at its full acceleration, run
    main-7: 47 of 49 applicable scenarios passed under 210, and `cycles/drilling` failed by
    1.8 mm under 209), 210; None for a version not recognised."""
    if planner == "exact":
        return 210.0
    m = re.match(r"^(?:\d+:)?(\d+)\.(\d+)", version or "")
    if not m:
        return None
    major, minor = int(m.group(1)), int(m.group(2))
    if (major, minor) < (2, 9):
        return None
    return 209.0 if (major, minor) == (2, 9) else 210.0


def machine_config(params, path_mode="G64", planner="default", runs_planner=None):
    """(ini_text, hal_text, cfg) for the parameters; cfg holds what the agent and the trace need
    (servo period, override limits, zero-speed time, the power-on path mode). Raises NotApplicable.
    `path_mode`: LinuxCNC's default G64 (blending), G61 (exact path) or G61.1 (exact stop).
    `planner`: "default", or "exact": LinuxCNC's planner joins colinear moves without a stop and
    cuts the acceleration of moves meeting at a corner by [TRAJ] ARC_BLEND_KINK_RATIO (0.1) in
    exact path mode too, and canned cycles run in exact path whatever the mode (rs274 -g:
    SET_MOTION_CONTROL_MODE(CANON_EXACT_PATH) around a cycle; tp.c tpSetupTangent). A look-ahead
    depth below 2 turns that off: every corner is an exact stop at full acceleration.
    `runs_planner`: the `nc.trajectory_planner` of the LinuxCNC that will run (`planner_of`): a
    scenario whose reference is another planner is not applicable (the installed LinuxCNC cannot
    be another version)."""
    v = resolve(params)
    if runs_planner is not None and v["nc.trajectory_planner"] != runs_planner:
        raise NotApplicable(
            f"nc.trajectory_planner = {v['nc.trajectory_planner']:g}, while this LinuxCNC runs the "
            f"planner {runs_planner:g} (DEC-163): give conform --params with nc.trajectory_planner: "
            f"{runs_planner:g} (scripts/linuxcnc-conform does)")
    # Under 2.9's planner the power-on G64 P is the tolerance canon and the planner start with,
    # and the one a canned cycle restores (DEC-169): the reference must start with this LinuxCNC's.
    if runs_planner == 209.0 and path_mode.startswith("G64"):
        m = re.search(r"P([0-9.]+)", path_mode)
        want = float(m.group(1)) if m else 0.0
        if abs(v["nc.startup_g64_p_mm"] - want) > 1e-9:
            raise NotApplicable(
                f"nc.startup_g64_p_mm = {v['nc.startup_g64_p_mm']:g}, while this LinuxCNC powers on in "
                f"{path_mode} (DEC-169): give conform --params with nc.startup_g64_p_mm: {want:g} "
                f"(scripts/linuxcnc-conform does)")
    period_us = int(v["nc.period_us"])
    if period_us not in (1000, 2000, 4000, 8000):
        raise NotApplicable(f"nc.period_us = {period_us}: not a servo period of the model")
    vel = {a: v["nc.rapid_mm_min"][a] / 60.0 for a in AXES}
    acc = {}
    for a in AXES:
        ramp = v["nc.rapid_ramp_ms"][a]
        acc[a] = vel[a] / (ramp / 1000.0) if ramp > 0 else NO_RAMP_ACC
    feed_v = v["nc.feed_max_mm_min"] / 60.0
    feed_ramp = v["nc.feed_ramp_ms"]
    feed_a = feed_v / (feed_ramp / 1000.0) if feed_ramp > 0 else NO_RAMP_ACC
    # LinuxCNC has one velocity and one acceleration per axis for rapids and feeds alike, and
    # [TRAJ] limits that cap both. `nc-conform params --from-ini` (harness/src/ini.rs) reads the
    # cutting feed's limit as the smallest axis velocity and its time constant as that velocity
    # over the smallest acceleration: a scenario whose feed settings differ from what its axes
    # give cannot be set up on LinuxCNC.
    # The cutting time constant is whole milliseconds (params --from-ini rounds it): the same
    # within half a millisecond.
    v_min, a_min = min(vel.values()), min(acc.values())
    want = (round(v_min * 60, 6), round(v_min / a_min * 1000, 6))
    have = (round(feed_v * 60, 6), round(feed_v / feed_a * 1000, 6) if feed_ramp > 0 else 0.0)
    if want[0] != have[0] or abs(want[1] - have[1]) > 0.5:
        raise NotApplicable(
            f"nc.feed_max_mm_min {have[0]:g} / nc.feed_ramp_ms {have[1]:g}: LinuxCNC's feeds share the "
            f"axes' limits (the slowest axis gives {want[0]:g} mm/min in {want[1]:g} ms)"
        )
    smax = v["nc.spindle_max_rpm"]
    sramp = v["nc.spindle_ramp_ms"]
    spindle_acc = smax / (sramp / 1000.0) if sramp > 0 else NO_RAMP_ACC
    cfg = {
        "period_us": period_us,
        "feed_override_max": v["nc.feed_override_max_pct"] / 100.0,
        "spindle_override_min": v["nc.spindle_override_min_pct"] / 100.0,
        "spindle_override_max": v["nc.spindle_override_max_pct"] / 100.0,
        "zsp_ms": v["plc.zsp_ms"],
        "path_mode": path_mode,
        "planner": planner,
    }
    ini = [
        "# Written by examples/linuxcnc-adapter for one scenario's linuxcnc parameters.",
        "[EMC]", "VERSION = 1.1", "MACHINE = nc-conform-linuxcnc-adapter", "DEBUG = 0", "",
        "[DISPLAY]", "DISPLAY = ./lcnc_agent.py", "CYCLE_TIME = 0.100",
        "POSITION_OFFSET = RELATIVE", "POSITION_FEEDBACK = ACTUAL",
        f"MAX_FEED_OVERRIDE = {num(cfg['feed_override_max'])}",
        f"MIN_SPINDLE_OVERRIDE = {num(cfg['spindle_override_min'])}",
        f"MAX_SPINDLE_OVERRIDE = {num(cfg['spindle_override_max'])}",
        "PROGRAM_PREFIX = .", "",
        "[TASK]", "TASK = milltask", "CYCLE_TIME = 0.001", "",
        "[RS274NGC]", "PARAMETER_FILE = machine.var",
        f"RS274NGC_STARTUP_CODE = G17 G21 G40 G49 G54 G80 G90 G94 G99 G8 {path_mode}", "",
        "[EMCMOT]", "EMCMOT = motmod", "COMM_TIMEOUT = 1.0", "BASE_PERIOD = 0",
        f"SERVO_PERIOD = {period_us * 1000}", "",
        # LinuxCNC 2.9 runs the IO controller as its own program (2.10 ignores these two).
        "[EMCIO]", "EMCIO = io", "CYCLE_TIME = 0.001", "TOOL_TABLE = machine.tbl", "",
        "[HAL]", "HALFILE = machine.hal", "",
        "[TRAJ]", "COORDINATES = X Y Z", "LINEAR_UNITS = mm", "ANGULAR_UNITS = degree",
        f"DEFAULT_LINEAR_VELOCITY = {num(max(vel.values()))}",
        # [TRAJ] caps the vector speed and acceleration of every move, rapids included; the
        # reference's G0 is limited by its axes only (DEC-140), so the caps sit where the axes
        # together end (params --from-ini reads the same feed limit: the smallest axis').
        f"MAX_LINEAR_VELOCITY = {num(max(feed_v, math.hypot(*vel.values())))}",
        f"DEFAULT_LINEAR_ACCELERATION = {num(max(acc.values()))}",
        f"MAX_LINEAR_ACCELERATION = {num(math.hypot(*acc.values()))}",
        *(["ARC_BLEND_OPTIMIZATION_DEPTH = 1"] if planner == "exact" else []), "",
        "[KINS]", "KINEMATICS = trivkins", "JOINTS = 3", "",
        "[SPINDLE_0]", f"MAX_FORWARD_VELOCITY = {num(smax)}", f"MAX_REVERSE_VELOCITY = {num(smax)}", "",
    ]
    for i, a in enumerate(AXES):
        ini += [
            f"[AXIS_{a}]", f"MAX_VELOCITY = {num(vel[a])}", f"MAX_ACCELERATION = {num(acc[a])}",
            f"MIN_LIMIT = {num(-LIMIT_MM)}", f"MAX_LIMIT = {num(LIMIT_MM)}", "",
            f"[JOINT_{i}]", "TYPE = LINEAR", "HOME = 0", f"MAX_VELOCITY = {num(vel[a])}",
            f"MAX_ACCELERATION = {num(acc[a])}", f"BACKLASH = {num(v['nc.backlash_mm'][a])}",
            f"MIN_LIMIT = {num(-LIMIT_MM)}", f"MAX_LIMIT = {num(LIMIT_MM)}",
            "FERROR = 1.27", "MIN_FERROR = 0.254", "HOME_OFFSET = 0", "HOME_SEARCH_VEL = 0",
            "HOME_LATCH_VEL = 0", "HOME_SEQUENCE = 0", "",
        ]
    hal = HAL_TEMPLATE.replace("@SPINDLE_ACC@", num(spindle_acc))
    return "\n".join(ini) + "\n", hal, cfg


# LinuxCNC's lib/hallib core_sim.hal and sim_spindle_encoder.hal, with the spindle's ramp from the
# parameters, a stall switch in front of the simulated spindle (the `spindle_stall` fault), a servo
# cycle clock for the agent, and the sampler that records every servo cycle.
HAL_TEMPLATE = """\
loadrt [KINS]KINEMATICS
loadrt [EMCMOT]EMCMOT base_period_nsec=[EMCMOT]BASE_PERIOD servo_period_nsec=[EMCMOT]SERVO_PERIOD num_joints=[KINS]JOINTS
addf motion-command-handler servo-thread
addf motion-controller servo-thread
net Xpos joint.0.motor-pos-cmd => joint.0.motor-pos-fb
net Ypos joint.1.motor-pos-cmd => joint.1.motor-pos-fb
net Zpos joint.2.motor-pos-cmd => joint.2.motor-pos-fb
net estop-loop iocontrol.0.user-enable-out iocontrol.0.emc-enable-in
net tool-prep-loop iocontrol.0.tool-prepare iocontrol.0.tool-prepared
net tool-change-loop iocontrol.0.tool-change iocontrol.0.tool-changed

# simulated spindle with encoder index (sim_spindle_encoder.hal), ramp @SPINDLE_ACC@ rpm/s
loadrt sim_spindle names=sim_spindle
setp sim_spindle.scale 0.01666667
loadrt limit2 names=limit_speed
loadrt lowpass names=spindle_mass
loadrt near names=near_speed
loadrt scale names=rpm_rps
loadrt mux2 names=stall,estop_spindle
setp rpm_rps.gain .0167
setp limit_speed.maxv @SPINDLE_ACC@
net spindle-index-enable spindle.0.index-enable <=> sim_spindle.index-enable
net spindle-pos sim_spindle.position-fb => spindle.0.revs
setp spindle_mass.gain .07
net spindle-speed-cmd spindle.0.speed-out => estop_spindle.in0
net spindle-speed-estop estop_spindle.out => limit_speed.in
net spindle-speed-drive limit_speed.out => stall.in0
setp stall.in1 0
setp stall.sel 0
net spindle-speed-limited stall.out => sim_spindle.velocity-cmd spindle_mass.in
net spindle-rpm-filtered spindle_mass.out
net spindle-rpm-filtered rpm_rps.in
net spindle-rps-filtered rpm_rps.out spindle.0.speed-in
# at-speed when the ramp has reached the command (the reference's machine: LCNC-MOT-01, DEC-143);
# a stalled spindle never is
setp near_speed.scale 1.0
setp near_speed.difference 0.5
net spindle-speed-cmd => near_speed.in1
net spindle-speed-limited => near_speed.in2
net spindle-at-speed near_speed.out spindle.0.at-speed
addf estop_spindle servo-thread
addf limit_speed servo-thread
addf stall servo-thread
addf spindle_mass servo-thread
addf rpm_rps servo-thread
addf near_speed servo-thread
addf sim_spindle servo-thread

# servo cycle clock (seconds of servo time) for the agent
loadrt integ names=servo_clock
setp servo_clock.in 1
addf servo_clock servo-thread

# E-stop at a servo cycle (the `emergency_stop` input), as an E-stop chain wired to motion's
# enable: the agent sets estop_at.in0 to the servo time before the cycle; from that cycle on
# motion.enable is false (motion stops in that cycle: control.c check_for_faults, then
# set_operating_mode clears the planner) and the spindle command is 0, braking through its ramp (as
# the task's E-stop does, emcSpindleAbort). estop_at and estop_ok run first in the servo cycle (on
# the clock of the cycle before), estop_spindle between motion and the spindle's ramp.
loadrt comp names=estop_at
loadrt not names=estop_ok
setp estop_at.in0 1e12
setp estop_spindle.in1 0
net estop-trip estop_at.out => estop_ok.in estop_spindle.sel
net estop-ok estop_ok.out => motion.enable
addf estop_at servo-thread 1
addf estop_ok servo-thread 2

# every servo cycle into the sampler FIFO (read by halsampler); columns: see lcnc_trace.COLUMNS
loadrt sampler depth=65536 cfg=fffffffbbbbbbbbss
setp sampler.0.enable 0
net Xpos => sampler.0.pin.0
net Ypos => sampler.0.pin.1
net Zpos => sampler.0.pin.2
net spindle-speed-limited => sampler.0.pin.3
net spindle-pos => sampler.0.pin.4
net spindle-speed-cmd => sampler.0.pin.5
net clock servo_clock.out => sampler.0.pin.6 estop_at.in1
net sp-on spindle.0.on => sampler.0.pin.7
net sp-fwd spindle.0.forward => sampler.0.pin.8
net sp-rev spindle.0.reverse => sampler.0.pin.9
net spindle-at-speed => sampler.0.pin.10
net spindle-index-enable => sampler.0.pin.11
net in-pos motion.in-position => sampler.0.pin.12
net flood iocontrol.0.coolant-flood => sampler.0.pin.13
net mist iocontrol.0.coolant-mist => sampler.0.pin.14
net prog-line motion.program-line => sampler.0.pin.15
net mot-type motion.motion-type => sampler.0.pin.16
addf sampler.0 servo-thread
"""


def running_linuxcnc():
    """Process ids of a LinuxCNC already running on this machine (any user's). Exited processes
    not yet reaped by their parent (zombies: another user's LinuxCNC just shut down) hold nothing
    and are not counted: waiting for them failed scenarios with "another LinuxCNC is still
    running" after another engineer's run."""
    out = subprocess.run(["pgrep", "-f", "rtapi_app|milltask|linuxcncsvr"], capture_output=True, text=True)
    return [int(p) for p in out.stdout.split() if not zombie(int(p))]


def zombie(pid):
    """The process has exited (state Z or X in /proc/PID/stat) or is gone."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] in ("Z", "X")
    except (OSError, IndexError):
        return True


def log(*a):
    print("lcnc-adapter:", *a, file=sys.stderr, flush=True)


class Instance:
    """One LinuxCNC instance running one machine configuration, driven through its agent.

    LinuxCNC instances cannot share a machine: the instance holds `lock_path` (flock, as
    `flock /tmp/linuxcnc.lock CMD` does) while it runs, and waits first until no other LinuxCNC
    process is left."""

    def __init__(self, ini, hal, user, lock_path, start_timeout=120.0):
        self.user = user
        self.proc = None
        self.conn = None
        self.lock = open(lock_path, "a")
        t0 = time.monotonic()
        fcntl.flock(self.lock, fcntl.LOCK_EX)
        while running_linuxcnc():
            if time.monotonic() - t0 > start_timeout:
                self.lock.close()
                raise RuntimeError("another LinuxCNC is still running (pgrep rtapi_app|milltask|linuxcncsvr)")
            time.sleep(1.0)
        self.dir = tempfile.mkdtemp(prefix="lcnc-adapter.")
        for name, text in (("machine.ini", ini), ("machine.hal", hal), ("machine.tbl", "T1 P1 D0 Z0 ;\n")):
            with open(os.path.join(self.dir, name), "w") as f:
                f.write(text)
        for name in ("lcnc_agent.py", "lcnc_step.py"):
            shutil.copy(os.path.join(HERE, name), os.path.join(self.dir, name))
        os.chmod(os.path.join(self.dir, "lcnc_agent.py"), 0o755)
        sock_path = os.path.join(self.dir, "agent.sock")
        self.server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.server.bind(sock_path)
        self.server.listen(1)
        self.server.settimeout(start_timeout)
        env = {
            "PATH": "/usr/sbin:/usr/bin:/sbin:/bin",
            "HOME": self.dir,
            "LCNC_AGENT_SOCK": sock_path,
        }
        cmd = ["linuxcnc", "-r", "machine.ini"]
        if os.getuid() == 0:
            uid = pwd.getpwnam(user)
            for root, dirs, files in os.walk(self.dir):
                for n in dirs + files + ["."]:
                    os.chown(os.path.join(root, n) if n != "." else root, uid.pw_uid, uid.pw_gid)
            os.chmod(self.dir, 0o755)
            cmd = ["runuser", "-u", user, "--", "env"] + [f"{k}={v}" for k, v in env.items()] + cmd
            env = None
        self.logf = open(os.path.join(self.dir, "linuxcnc.log"), "w")
        self.proc = subprocess.Popen(cmd, cwd=self.dir, env=env, stdout=self.logf, stderr=subprocess.STDOUT,
                                     stdin=subprocess.DEVNULL, start_new_session=True)
        try:
            self.conn, _ = self.server.accept()
        except socket.timeout:
            self.close()
            raise RuntimeError("LinuxCNC did not start its agent: " + self.log_tail())
        self.conn.settimeout(None)
        self.prioritise()
        self.rfile = self.conn.makefile("r")
        hello = self.receive()
        if not hello.get("ok"):
            why = hello.get("error", "?")
            self.close()
            raise RuntimeError("LinuxCNC's agent failed to start: " + why)
        self.version = hello.get("version", "?")

    def prioritise(self):
        """LinuxCNC wants a real-time kernel; on an ordinary one its processes (servo thread,
        task, the agent that gives the inputs) at least get a higher priority than the rest of
        the machine when root can give it (nice -10), so that inputs are given on time."""
        if os.getuid() != 0:
            return
        out = subprocess.run(["pgrep", "-u", self.user], capture_output=True, text=True).stdout.split()
        for pid in out:
            try:
                os.setpriority(os.PRIO_PROCESS, int(pid), -10)
            except OSError:
                pass

    def log_tail(self, n=2000):
        try:
            with open(os.path.join(self.dir, "linuxcnc.log")) as f:
                return f.read()[-n:]
        except OSError:
            return ""

    def receive(self):
        line = self.rfile.readline()
        if not line:
            raise RuntimeError("LinuxCNC's agent stopped: " + self.log_tail())
        return json.loads(line)

    def call(self, request):
        self.conn.sendall((json.dumps(request) + "\n").encode())
        return self.receive()

    def alive(self):
        return self.proc is not None and self.proc.poll() is None

    def close(self):
        """Shuts LinuxCNC down (the agent's exit ends the `linuxcnc` script), then makes sure no
        rtapi_app of the user is left, and releases the lock."""
        if self.conn is not None:
            try:
                self.conn.sendall(b'{"op":"quit"}\n')
            except OSError:
                pass
        if self.proc is not None:
            try:
                self.proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, 15)
                try:
                    self.proc.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    os.killpg(self.proc.pid, 9)
            for _ in range(100):
                if not running_linuxcnc():
                    break
                time.sleep(0.1)
            else:
                subprocess.run(["runuser", "-u", self.user, "--", "halrun", "-U"] if os.getuid() == 0
                               else ["halrun", "-U"], capture_output=True)
        self.proc = None
        try:
            self.server.close()
        except OSError:
            pass
        try:
            self.logf.close()
        except (OSError, AttributeError):
            pass
        shutil.rmtree(self.dir, ignore_errors=True)
        self.lock.close()
