#!/usr/bin/env python3
"""A toy controller behind the nc-conform adapter protocol (docs/adapter-protocol.md).

The toy does the protocol side itself -- the handshake with its own name and version, the
dialects it claims, the checks of every request -- and delegates the machine to the reference
engine (`nc-conform serve`), which it runs as a child process. Replace `Machine` with calls into
your own controller (a simulator, a PLC bridge, a machine on the bench) and keep the rest.

Usage: toy_adapter.py [--nc-conform PATH] [--dialects gsk-lathe,fanuc-mill]
Without --nc-conform it finds the engine itself (see `find_nc_conform`), so that
`nc-conform conform --adapter "python3 examples/python-adapter/toy_adapter.py"` works as written.
Standard library only.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys

PROTOCOL = "nc-conform-adapter/1"


class Machine:
    """The toy's machine: the reference engine over the same protocol."""

    def __init__(self, nc_conform):
        self.proc = subprocess.Popen(
            [nc_conform, "serve"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
        )
        self.call({"op": "hello", "protocol": PROTOCOL})

    def call_raw(self, request):
        """The answer line as written: trace numbers are exact decimals, and a float round trip
        through json would turn 0.000001 into 1e-06."""
        self.proc.stdin.write(json.dumps(request) + "\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError("the machine stopped answering")
        return line.rstrip("\n")

    def call(self, request):
        return json.loads(self.call_raw(request))

    def close(self):
        try:
            self.call({"op": "quit"})
        finally:
            self.proc.wait(timeout=5)


def find_nc_conform():
    """The nc-conform binary when --nc-conform is not given: $NC_CONFORM if set, else the
    nc-conform that started this adapter (`nc-conform conform` is its parent process; Linux's
    /proc names its executable), else `nc-conform` on the PATH."""
    if os.environ.get("NC_CONFORM"):
        return os.environ["NC_CONFORM"]
    try:
        parent = os.readlink(f"/proc/{os.getppid()}/exe")
        if os.path.basename(parent).startswith("nc-conform"):
            return parent
    except OSError:
        pass
    return shutil.which("nc-conform") or "nc-conform"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--nc-conform", default=None, help="the nc-conform binary (default: see find_nc_conform)")
    ap.add_argument("--dialects", default="gsk-lathe,fanuc-mill,knd-lathe")
    args = ap.parse_args()
    dialects = [d for d in args.dialects.split(",") if d]
    machine = Machine(args.nc_conform or find_nc_conform())
    for line in sys.stdin:
        if not line.strip():
            continue
        request = json.loads(line)
        op = request.get("op")
        answer = None
        if op == "hello":
            if request.get("protocol") != PROTOCOL:
                answer = {"ok": False, "protocol": PROTOCOL, "error": "unsupported protocol"}
            else:
                answer = {"ok": True, "protocol": PROTOCOL, "name": "toy-python",
                          "version": "0.1", "dialects": dialects}
        elif op == "load" and request.get("dialect") not in dialects:
            answer = {"ok": False, "unsupported": "the toy does not run " + str(request.get("dialect"))}
        elif op == "quit":
            answer = {"ok": True}
        else:
            # load, input, advance, read, reset: the machine answers, passed on as written.
            sys.stdout.write(machine.call_raw(request) + "\n")
        if answer is not None:
            sys.stdout.write(json.dumps(answer) + "\n")
        sys.stdout.flush()
        if op == "quit":
            break
    machine.close()


if __name__ == "__main__":
    main()
