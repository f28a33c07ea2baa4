#!/usr/bin/env python3
"""Headless 'display' for LinuxCNC ([DISPLAY] DISPLAY = ./driver.py): homes,
then for each program named in $LCNC_PROGRAMS (space separated, default:
g331 g84 g81) moves to X0 Y0 Z0 (G53), starts halsampler, runs
$LCNC_PROG_DIR/PROGRAM.ngc (default ../programs) in AUTO mode, waits until it
has finished and the spindle has stopped, and writes $LCNC_OUT/PROGRAM.txt
(default rec/; halsampler -t output: sample number, then the pins of
record.hal in order)."""
import os, subprocess, sys, time
import linuxcnc

out_dir = os.environ.get("LCNC_OUT", "rec")
prog_dir = os.environ.get("LCNC_PROG_DIR", "../programs")
progs = os.environ.get("LCNC_PROGRAMS", "g331 g84 g81").split()
os.makedirs(out_dir, exist_ok=True)
c, s, e = linuxcnc.command(), linuxcnc.stat(), linuxcnc.error_channel()

def log(*a):
    print("driver:", *a, flush=True)

def errors():
    m = e.poll()
    while m:
        log("LinuxCNC message:", m)
        m = e.poll()

def wait(cond, timeout, what):
    t0 = time.time()
    while time.time() - t0 < timeout:
        s.poll()
        if cond():
            return
        errors()
        time.sleep(0.01)
    raise SystemExit("driver: timeout waiting for " + what)

def setp(pin, v):
    subprocess.run(["halcmd", "setp", pin, str(v)], check=True)

wait(lambda: True, 10, "status")

def machine_on():
    # Task may take commands before iocontrol/motion are ready (Debian's 2.9 runs iocontrol
    # as its own process): repeat E-stop reset and machine on until the state shows it.
    for _ in range(30):
        s.poll()
        if s.task_state == linuxcnc.STATE_ON:
            return
        if s.task_state == linuxcnc.STATE_ESTOP:
            c.state(linuxcnc.STATE_ESTOP_RESET)
        else:
            c.state(linuxcnc.STATE_ON)
        c.wait_complete(1.0)
        time.sleep(0.2)
        errors()
    raise SystemExit("driver: the machine does not turn on")

machine_on()
c.mode(linuxcnc.MODE_MANUAL); c.wait_complete()
c.teleop_enable(0); c.wait_complete()
c.home(-1)
wait(lambda: all(s.homed[i] for i in range(3)), 20, "homing")
log("homed")

for p in progs:
    c.mode(linuxcnc.MODE_MDI); c.wait_complete()
    c.mdi("G53 G0 X0 Y0 Z0"); c.wait_complete()
    wait(lambda: s.interp_state == linuxcnc.INTERP_IDLE and s.inpos, 30, "MDI")
    c.mode(linuxcnc.MODE_AUTO); c.wait_complete()
    c.program_open(os.path.abspath(os.path.join(prog_dir, p + ".ngc"))); c.wait_complete()
    f = open(os.path.join(out_dir, p + ".txt"), "w")
    hs = subprocess.Popen(["halsampler", "-t", "-c", "0"], stdout=f)
    time.sleep(0.3)
    setp("sampler.0.enable", 1)
    time.sleep(0.1)                      # 100 ms at rest before the start
    c.auto(linuxcnc.AUTO_RUN, 0)
    wait(lambda: s.interp_state != linuxcnc.INTERP_IDLE, 5, "program start")
    wait(lambda: s.interp_state == linuxcnc.INTERP_IDLE, 120, p + " end")
    wait(lambda: abs(s.spindle[0]["speed"]) < 1e-9, 10, "spindle cmd 0")
    time.sleep(0.5)                      # spindle ramp down (5000 rpm/s) and rest
    setp("sampler.0.enable", 0)
    time.sleep(0.5)
    hs.terminate(); hs.wait(); f.close()
    errors()
    log(p, "recorded")

c.state(linuxcnc.STATE_OFF); c.wait_complete()
log("done")
