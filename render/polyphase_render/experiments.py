"""Published measurements the scenes' own measurements are compared with."""

import math

#: Martin & Moyce (1952), "An experimental study of the collapse of liquid columns on a rigid
#: horizontal plane", Phil. Trans. R. Soc. A 244, 312-324: surge front of a water column of
#: width a = 2.25 in and height 2a (n² = 2), as digitised points (T, Z) with Z = front / a and
#: T = t·sqrt(g/a). Z steps by 0.5 in / a, the spacing of the measuring marks.
MARTIN_MOYCE_N2 = (
    (0.43, 1.11), (0.62, 1.22), (0.80, 1.44), (0.97, 1.67), (1.14, 1.89), (1.29, 2.11),
    (1.45, 2.33), (1.62, 2.56), (1.76, 2.78), (1.93, 3.00), (2.07, 3.22), (2.24, 3.44),
    (2.40, 3.67), (2.54, 3.89), (2.71, 4.11), (2.87, 4.33), (3.04, 4.56), (3.21, 4.78),
    (3.29, 4.89), (3.32, 5.00),
)


def surge_front_dimensionless(times, fronts, g=9.81):
    """(T, Z) of a simulated surge front, scaled like Martin & Moyce: a is the column's width,
    the front's position at the first time (the column starts against the wall at x = 0)."""
    a = fronts[0]
    return [t * math.sqrt(g / a) for t in times], [x / a for x in fronts]


def interpolate(xs, ys, x):
    """Piecewise-linear y(x) over increasing xs; None outside their range."""
    for (x0, y0), (x1, y1) in zip(zip(xs, ys), zip(xs[1:], ys[1:])):
        if x0 <= x <= x1:
            return y0 + (y1 - y0) * (x - x0) / (x1 - x0) if x1 > x0 else y0
    return None
