(A pocket contour, as a CAM post-processor writes it: lines, tangent arcs,)
(a helical turn down to the next level. mm, origin at home.)
%
N10 G21 G90 G17 G94 G61
N20 F30000
N30 G1 X50 Y0 Z0
N40 G3 X70 Y20 I0 J20
N50 G1 Y60
N60 G3 X50 Y80 I-20 J0
N70 G1 X-50
N80 G3 X-70 Y60 J-20
N90 G1 Y20
N100 G3 X-50 Y0 I20
N110 G1 X0
N120 G2 X0 Y0 Z-30 I0 J40 (the helical turn)
N130 G1 Z-60
N140 M30
%
