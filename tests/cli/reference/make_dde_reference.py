#!/usr/bin/env python3
"""Reference rightmost roots for the linear_dde studies of tests/cli/studies (dde_*.toml).

Not run by the tests (they only read dde_rightmost_roots.csv): kept so the pinned values can be
re-derived. Independent of chatterlab: the scalar characteristic equation written out by hand,

    x'' + 0.1 x' + 1.3 x = b x(t - tau)   ->   s^2 + 0.1 s + 1.3 - b exp(-tau s) = 0,

(b = 0.3 is the DDE-BIFTOOL test x'' + 2 zeta x' + x = -K (x - x(t - tau)), zeta 0.05, K 0.3),
a dense multi-start Newton in double precision over Re s in [-3, 1], 0 <= Im s <= 2 pi * 1.2 Hz,
then every distinct root polished with mpmath at 40 digits; the rightmost with |Im s| <= 2 pi
(the studies' band, max_frequency_hz = 1) is printed. Needs: python3 with mpmath.
"""
import cmath
import math

import mpmath as mp

mp.mp.dps = 40
BAND = 2 * math.pi * 1.0


def newton(b, tau, s):
    for _ in range(100):
        e = cmath.exp(-tau * s)
        f = s * s + 0.1 * s + 1.3 - b * e
        df = 2 * s + 0.1 + b * tau * e
        step = f / df
        s -= step
        if abs(step) < 1e-13 * max(1.0, abs(s)):
            return s
        if abs(s) > 50:
            return None
    return None


def rightmost(b, tau):
    found = []
    for i in range(81):
        for j in range(161):
            s = newton(b, tau, complex(-3 + 4 * i / 80, 1.2 * BAND * j / 160))
            if s is None or abs(s.imag) > BAND:
                continue
            s = complex(s.real, abs(s.imag))
            if all(abs(s - r) > 1e-8 for r in found):
                found.append(s)
    best = max(found, key=lambda r: r.real)
    bm, taum = mp.mpf(b), mp.mpf(tau)
    f = lambda s: s * s + mp.mpf("0.1") * s + mp.mpf("1.3") - bm * mp.exp(-taum * s)
    polished = mp.findroot(f, mp.mpc(best.real, best.imag))
    return polished, len(found)


print("b,delay_s,growth_rate_per_s,chatter_frequency_hz")
for b, taus in ((0.3, (2.0, 5.0)), (0.1, (2.0, 4.0, 6.0, 8.0, 10.0)), (0.2, (2.0, 4.0, 6.0, 8.0, 10.0)),
                (0.3, (4.0, 6.0, 8.0, 10.0)), (0.4, (2.0, 4.0, 6.0, 8.0, 10.0))):
    for tau in taus:
        r, n = rightmost(b, tau)
        print(f"{b},{tau},{mp.nstr(r.real, 17)},{mp.nstr(abs(r.imag) / (2 * mp.pi), 17)}")
