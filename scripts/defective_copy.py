#!/usr/bin/env python3
"""A copy of a `check_rss write` recording with defects, to compare the reports of two builds of
`nc-conform check` on a divergent recording (docs/checking.md, "Performance").

    python3 scripts/defective_copy.py /tmp/perf14/k2 /tmp/perf14/k2d

writes k2d.csv (Z offsets over 40 rows, spindle angle +40 deg on every other row of 300, an RGTAP
glitch, a 2 mm spike every 97,000 rows) and k2d.jsonl (RGSPP/RGSPM lines dropped now and then, Z
+0.3 mm over 50 lines), and copies the program and the map.
"""
import json
import shutil
import sys

src, dst = sys.argv[1], sys.argv[2]
lines = open(src + '.csv').read().split('\n')
out = [lines[0]]
for i, line in enumerate(lines[1:], 1):
    if not line:
        out.append(line)
        continue
    f = line.split(',')
    if 200000 <= i < 200040:
        f[3] = str(float(f[3]) + 0.4)
    if 400000 <= i < 400300 and i % 2 == 0:
        f[5] = str((float(f[5]) + 40) % 360)
    if 600000 <= i < 600004:
        f[6] = str(int(f[6]) ^ 2)
    if i % 97000 == 0:
        f[3] = str(float(f[3]) + 2.0)
    out.append(','.join(f))
open(dst + '.csv', 'w').write('\n'.join(out))
with open(dst + '.jsonl', 'w') as w:
    for n, line in enumerate(open(src + '.jsonl'), 1):
        if '"kind":"signal"' in line and n % 5000 < 40 and 'RGSP' in line:
            continue
        if 300000 <= n < 300050 and '"kind":"sample"' in line:
            d = json.loads(line)
            d['axes']['Z'] = round(d['axes']['Z'] + 0.3, 6)
            line = json.dumps(d, separators=(',', ':')) + '\n'
        w.write(line)
shutil.copy(src + '.nc', dst + '.nc')
shutil.copy(src + '.map.yaml', dst + '.map.yaml')
