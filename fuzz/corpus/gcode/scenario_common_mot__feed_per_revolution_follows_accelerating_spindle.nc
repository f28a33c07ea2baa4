S600 M3;
G99 G1 Z-1 F0.1;         starts at 40 ms, when the spindle turns at 96 rpm
M30;
