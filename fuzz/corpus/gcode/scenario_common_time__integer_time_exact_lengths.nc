G98;
G0 X12.3456 Z-0.0001;
G1 Z-5.0001 F600;    10 ms ramp to 10 mm/s, then 10 mm/s
M30;
