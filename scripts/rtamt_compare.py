#!/usr/bin/env python3
"""RTAMT side of the issue-6 performance comparison (a measurement tool, not a CI test).

Writes (or reads) the 1-hour, 1 kHz, 8-column CSV trace of `nc_conform::import::gen` (same
header, same rows: `time_ms,X,Y,Z,S_rpm,S_deg,flags,load`, flags bit 0 = RGTAP, bit 3 = F76.3)
and evaluates ONE temporal rule offline with RTAMT's discrete-time STL monitor:

    always ((F76.3 == 1) implies (RGTAP >= 0))      # signals as 0/1 series, 1 kHz

(`RGTAP >= 0` holds everywhere, so the monitor walks the whole trace without an early verdict;
the same rule shape as an `always: {while: {F76.3: 1}, holds: {...}}` of a scenario.)

Timed: the monitor's evaluation only (`spec.evaluate`), the CSV parsing excluded; the parse time
is printed separately.

Usage:
    pip install rtamt
    python3 scripts/rtamt_compare.py --write /tmp/gen_1h.csv          # write the trace (once)
    python3 scripts/rtamt_compare.py /tmp/gen_1h.csv [ROWS]            # time the rule
"""
import sys
import time

HEADER = "time_ms,X,Y,Z,S_rpm,S_deg,flags,load\n"
TAILS = 1000


def tails():
    out = []
    for r in range(TAILS):
        z = -((r % 500)) * 0.0015
        out.append(",%d.%03d,12.5,%.6f,%d,%d.%d,%d,%d\n" % (
            r % 100, r % 1000, z, (r % 300) - 150, r % 360, r % 10, (r // 50) % 16, r % 97))
    return out


def write(path, rows):
    t = tails()
    with open(path, "w") as f:
        f.write(HEADER)
        chunk = []
        for r in range(rows):
            chunk.append("%d%s" % (r, t[r % TAILS]))
            if len(chunk) == 65536:
                f.write("".join(chunk))
                chunk = []
        f.write("".join(chunk))


def read(path, rows):
    times, f76, rgtap = [], [], []
    with open(path) as f:
        f.readline()
        for i, line in enumerate(f):
            if i >= rows:
                break
            flags = int(line.split(",")[6])
            times.append(i)
            f76.append(float(flags >> 3 & 1))
            rgtap.append(float(flags & 1))
    return {"time": times, "f76": f76, "rgtap": rgtap}


def main():
    if len(sys.argv) >= 3 and sys.argv[1] == "--write":
        rows = int(sys.argv[3]) if len(sys.argv) > 3 else 3_600_000
        write(sys.argv[2], rows)
        return
    import rtamt

    path = sys.argv[1]
    rows = int(sys.argv[2]) if len(sys.argv) > 2 else 3_600_000
    t0 = time.perf_counter()
    data = read(path, rows)
    t1 = time.perf_counter()
    spec = rtamt.StlDiscreteTimeOfflineSpecification()
    spec.name = "F76.3 implies RGTAP >= 0"
    spec.declare_var("f76", "float")
    spec.declare_var("rgtap", "float")
    spec.spec = "always ((f76 >= 0.5) implies (rgtap >= 0))"
    spec.parse()
    t2 = time.perf_counter()
    rob = spec.evaluate(data)
    t3 = time.perf_counter()
    print("rows %d, parse CSV %.3f s, rtamt evaluate %.3f s, robustness at 0: %s"
          % (len(data["time"]), t1 - t0, t3 - t2, rob[0][1]))


if __name__ == "__main__":
    main()
