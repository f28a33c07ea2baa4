%
O1234 (NAME)
/N10 G0 X10 Z5 ; comment
(paren comment)
N20 G1 X0.5 Z-1. F0.1
%
