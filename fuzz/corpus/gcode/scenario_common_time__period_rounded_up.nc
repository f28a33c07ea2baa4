G98;
G1 Z-9.905 F600;   990.5 ms at 10 mm/s plus a 10 ms ramp: 1000.5 ms ideal
G4 P5;
M30;
