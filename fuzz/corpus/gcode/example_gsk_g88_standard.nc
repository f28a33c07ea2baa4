%
O0002 (GSK 980TDi rigid tapping, standard cycle, seed 000)
G98;          feed per minute
G0 X50 Z0;    hole position
M29 S1000;    rigid tapping mode
G88 X-50 P3000 F2;  bottom X-50, dwell 3 s, lead 2
G80;
M30;
%
