#!/usr/bin/env python3
"""Writes the seed corpora of the structured fuzz targets (`cli_files`, `nesting`,
`adapter_lines`) into fuzz/corpus/<target>/.

Their inputs are decoded with `arbitrary` 1.x: an enum is a little-endian u32 mapped onto its
variants by multiply-and-shift, integers are little-endian, a bool is the low bit of a byte, and
a `take_rest` vector is a sequence of (1, element) pairs. `cli_files` reads its role and source
that way and takes the rest of the input as the file's bytes. Run from the repository root:
`python3 fuzz/make_seeds.py` (only the standard library)."""
import os
import struct

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def tag(r, n):
    """The u32 that `arbitrary` maps onto variant r of n."""
    return struct.pack("<I", -(-(r << 32) // n))


def u8(v):
    return bytes([v])


def u32(v):
    return struct.pack("<I", v)


def u64(v):
    return struct.pack("<Q", v)


def read(path):
    with open(os.path.join(ROOT, path), "rb") as f:
        return f.read()


def write(target, name, data):
    d = os.path.join(ROOT, "fuzz", "corpus", target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


# cli_files: Role (6 variants), Source (6 variants), then the file's bytes.
GSK, FANUC, KND, LCNC, HEI = range(5)
FILE, REPEATED, DEV_ZERO, DEV_NULL, DIRECTORY, MISSING = range(6)


def role(r, *payload):
    return tag(r, 6) + b"".join(payload)


def source(s, *payload):
    return tag(s, 6) + b"".join(payload)


programs = {
    "gsk_g92_3.nc": GSK, "gsk_g88_peck.nc": GSK, "fanuc_g84_seed.nc": FANUC, "knd_g93.nc": KND,
    "heidenhain_832_seed.h": HEI,
}
for name, d in programs.items():
    write("cli_files", f"program_{name}", role(0, u8(d)) + source(FILE) + read(f"examples/{name}"))
write("cli_files", "program_linuxcnc_cycles.ngc",
      role(0, u8(LCNC)) + source(FILE) + read("fuzz/corpus/gcode/example_linuxcnc_cycles.ngc"))
write("cli_files", "program_2mb_of_comments.nc",
      role(0, u8(GSK)) + source(REPEATED, u32(200_000)) + b"(a comment line)\n")
write("cli_files", "program_dev_null", role(0, u8(FANUC)) + source(DEV_NULL))
write("cli_files", "program_directory", role(0, u8(KND)) + source(DIRECTORY))
write("cli_files", "program_missing", role(0, u8(LCNC)) + source(MISSING))
for i, name in enumerate(["reset_in_rigid_tapping.yaml", "g76_fine_bore_orient.yaml"]):
    sub = "cancel" if i == 0 else "cycles"
    write("cli_files", f"scenario_{name}", role(1, u8(i)) + source(FILE) + read(f"scenarios/fanuc/{sub}/{name}"))
write("cli_files", "params_gsk.yaml", role(2, u8(GSK)) + source(FILE) + (
    b'params:\n  170: 68\n  "186.2": 1\n  271: 120\n  34: {X: 0.01, Z: 0.005}\n'
    b"  nc.rapid_mm_min:\n    X: 4000\n    Z: 8000\n"))
write("cli_files", "params_fanuc.yaml", role(2, u8(FANUC)) + source(FILE) + b"params:\n  5200.6: 1\n  nc.period_us: 2000\n")
for k, (fmt, name) in enumerate([("jsonl", "gsk_peck.jsonl"), ("csv", "basic.csv"), ("vcd", "small.vcd"),
                                  ("shdr", "basic.shdr")]):
    write("cli_files", f"trace_{name}", role(3, u8(k), u8(0)) + source(FILE) + read(f"fuzz/corpus/import_{fmt}/{name}"))
write("cli_files", "map.yaml", role(4) + source(FILE) + (
    b"time: {column: t, unit: ms}\naxes:\n  - {axis: X, column: x}\n  - {axis: Z, column: z}\n"
    b"spindle:\n  rpm: {column: s}\n"))
write("cli_files", "tolerances.yaml", role(5) + source(FILE) + (
    b"event_ms: 20\nevent_windows_ms:\n  FIN: 50\n  M29: 40\nposition_mm: 0.05\nenvelope_ms: 20\n"
    b"keypoint_mm: 0.02\ndwell_ms: 20\nsync_mm: 0.02\nspeed_rpm: 5\n"))

# nesting: depth (u32), in_assignment (bool), Shape (7 variants; Expression takes the rest as
# (1, Level) pairs, Level of 6 variants).
def nesting(depth, assign, shape, *payload):
    return u32(depth) + u8(assign) + tag(shape, 7) + b"".join(payload)


def level(r, *payload):
    return b"\x01" + tag(r, 6) + b"".join(payload)


write("nesting", "brackets_40", nesting(40, 1, 0, level(0)))
write("nesting", "sin_minus_30", nesting(30, 0, 0, level(1, u8(0)), level(2)))
write("nesting", "atan_left_right_20", nesting(20, 1, 0, level(3), level(4, u8(0)), level(5, u8(2))))
write("nesting", "chain_plus_500", nesting(500, 1, 1, u8(0)))
write("nesting", "chain_power_50", nesting(50, 0, 1, u8(4)))
write("nesting", "if_30", nesting(30, 0, 2))
write("nesting", "while_30", nesting(30, 0, 3))
write("nesting", "repeat_30", nesting(30, 0, 4))
write("nesting", "recursion_5", nesting(5, 0, 5))
write("nesting", "vcd_scopes_50", nesting(50, 0, 6))

# adapter_lines: Then (5 variants), then the answers as (1, Answer) pairs, Answer of 10 variants.
EXIT, CLOSE_STDOUT, CLOSE_STDIN, SILENT, ENDLESS = range(5)


def answer(r, *payload):
    return b"\x01" + tag(r, 10) + b"".join(payload)


HELLO = answer(0, u8(1))
OK = answer(1)
ADVANCE_END = answer(5, u64(20_000_000), u8(1), u8(0))
REFERENCE = answer(7, u8(255))
write("adapter_lines", "good_adapter", tag(EXIT, 5) + HELLO + OK + ADVANCE_END + REFERENCE)
write("adapter_lines", "silent_after_hello", tag(SILENT, 5) + HELLO)
write("adapter_lines", "exits_at_once", tag(EXIT, 5))
write("adapter_lines", "half_the_events", tag(EXIT, 5) + HELLO + OK + ADVANCE_END + answer(7, u8(3)))
write("adapter_lines", "hello_of_gsk_only", tag(EXIT, 5) + answer(0, u8(0)))
