#!/usr/bin/env python3
"""The HTML page of a LinuxCNC conformance run (scripts/linuxcnc-conform): from the JSON report
of `nc-conform conform --report` and the adapter's log (--log).

Usage: report_html.py REPORT.json ADAPTER_LOG.jsonl OUT.html
Standard library only.
"""

import html
import json
import sys


def load_log(path):
    runs, starts, reruns = [], [], []
    try:
        with open(path) as f:
            for line in f:
                try:
                    e = json.loads(line)
                except ValueError:
                    continue
                {"run": runs, "start": starts, "rerun": reruns}.get(e.get("event"), []).append(e)
    except OSError:
        pass
    return runs, starts, reruns


def main():
    report_path, log_path, out_path = sys.argv[1:4]
    with open(report_path) as f:
        rep = json.load(f)
    runs, starts, reruns = load_log(log_path)
    esc = html.escape
    rows = []
    for v in rep["scenarios"]:
        st = v["status"]
        if isinstance(st, dict):  # {"skipped": "why"}
            label, why = "not applicable", next(iter(st.values()))
        else:
            label, why = st, ""
        fails = "".join(
            f"<li><b>{esc(f['rule'])}</b> [{esc(f['by'])}] {esc(f['text'])}</li>" for f in v["failures"]
        )
        notes = "".join(f"<li class='note'>{esc(n)}</li>" for n in v.get("notes", []))
        rows.append(
            f"<tr class='{label.replace(' ', '-')}'><td>{esc(v['name'])}</td><td>{esc(label)}</td>"
            f"<td>{v['seconds']:.1f}</td><td>{esc(v['title'])}<br><i>{esc(why)}</i><ul>{fails}{notes}</ul></td></tr>"
        )
    rules = "".join(
        f"<tr><td>{esc(r)}</td><td>{len(s['passed'])}</td><td>{len(s['failed'])}</td>"
        f"<td>{esc(', '.join(s['failed']))}</td></tr>"
        for r, s in rep["rules"].items()
    )
    lates = [abs(i["late_us"]) for r in runs for i in r.get("inputs", [])]
    moved = [abs(r["moved_us"]) for r in reruns if r.get("moved_us") is not None]
    wall = sum(r["seconds"] for r in runs) + sum(s["seconds"] for s in starts)

    def stat(xs):
        if not xs:
            return "-"
        xs = sorted(xs)
        return f"median {xs[len(xs) // 2] / 1000:g} ms, max {xs[-1] / 1000:g} ms ({len(xs)})"

    page = f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>LinuxCNC conformance: {esc(rep['controller'])}</title>
<style>body{{font-family:sans-serif}} td{{vertical-align:top;border-bottom:1px solid #ccc;padding:2px 6px}}
tr.passed td:nth-child(2){{color:green}} tr.failed td:nth-child(2){{color:#b00}}
tr.not-applicable td:nth-child(2){{color:#888}} li.note{{color:#666}} table{{border-collapse:collapse}}</style></head><body>
<h1>LinuxCNC conformance</h1>
<p>Controller: <b>{esc(rep['controller'])}</b> (Debian linuxcnc-uspace, simulator HAL, headless, through
examples/linuxcnc-adapter). Scenarios: {rep['passed']} passed, {rep['failed']} failed,
{rep['skipped']} not applicable.</p>
<p>LinuxCNC runs: {len(runs)} ({len(starts)} start-ups), {wall:.0f} s of LinuxCNC time in all.
Inputs given vs their due servo cycle: {stat(lates)}. Condition times moved between a run and its
re-run: {stat(moved)}.</p>
<h2>Scenarios</h2>
<table><tr><th>scenario</th><th>verdict</th><th>s</th><th>what</th></tr>
{''.join(rows)}</table>
<h2>Rules</h2>
<table><tr><th>rule</th><th>passed</th><th>failed</th><th>failing scenarios</th></tr>{rules}</table>
</body></html>
"""
    with open(out_path, "w") as f:
        f.write(page)


if __name__ == "__main__":
    main()
