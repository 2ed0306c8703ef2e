#!/usr/bin/env python3
"""Writes the synthetic probe data of the shipped error-separation studies (MODELS.md E1-E6).

Everything is in micrometres. Probe q at angle phi_q reads, at sample i of a revolution
(theta_i = 2 pi i / N, N = 360, one sample per degree),

    Y_q(i) = F(theta_i + phi_q) + dx(i) cos(phi_q) + dy(i) sin(phi_q)

with probes A, B, C at 0, 99, 202 degrees (gcd(99, 202, 360) = 1: no harmonic suppressed).
The true profile (docs/analysis/error_separation.md states it too):

    r(theta) = 2.0 cos(3 theta + 0.5) + 1.0 cos(5 theta) + 0.5 sin(18 theta) + 0.3 cos(40 theta + 1)
    F(theta) = 5.0 + r(theta) + 10.0 cos(theta - 0.3)     (mean offset 5, eccentricity 10 at 0.3 rad)
    dx = 1.5 cos(2 theta) + 0.8 sin(7 theta),  dy = 1.2 sin(2 theta + 0.4) - 0.5 cos(4 theta)

three_probe.csv: one revolution, no noise (the separated profile equals r exactly).
three_probe_noisy.csv: the same part and spindle seen by probes at 0, 97, 194 degrees (equally
spaced, as the time recursion needs), 8 revolutions with Gaussian probe noise sigma = 0.2 um
(seed 7), for ensemble averaging and FIR smoothing.
three_probe_opposite.csv: the part and spindle of three_probe.csv seen by probes at 0, 90 and
    180 degrees, one revolution, no noise: c1 = -sin(180)/sin(90) = 0, G(l) = 1 + e^{j l pi} and
    every odd harmonic is lost (the degraded-layout example).
cylinder_probes.csv: sections z_mm = 0, 20, 40, 60, 80 (one revolution each) of a part with
    F_j(theta) = dr(z) + r_j(theta) + cx(z) cos(theta) + cy(z) sin(theta),
    dr = 3 + 0.01 z, cx = 2 + 0.05 z, cy = -1 + 0.0005 z^2,
    r_j = (2.0 + 0.01 z) cos(3 theta + 0.5) + 0.5 sin(18 theta),
and a slide that is not straight: dx, dy above plus u = 0.3 sin(z / 25), v = 0.2 z / 80.
"""
import math
import os
import random

N = 360
ANGLES_DEG = (0.0, 99.0, 202.0)
EQUAL_DEG = (0.0, 97.0, 194.0)  # time recursion: 0, p, 2p with gcd(97, 360) = 1
OPPOSITE_DEG = (0.0, 90.0, 180.0)  # loses every odd harmonic
HERE = os.path.dirname(os.path.abspath(__file__))


def r(theta):
    return (2.0 * math.cos(3 * theta + 0.5) + 1.0 * math.cos(5 * theta) + 0.5 * math.sin(18 * theta)
            + 0.3 * math.cos(40 * theta + 1))


def spindle(theta):
    return (1.5 * math.cos(2 * theta) + 0.8 * math.sin(7 * theta),
            1.2 * math.sin(2 * theta + 0.4) - 0.5 * math.cos(4 * theta))


def readings(form, theta, dx, dy, angles=ANGLES_DEG):
    out = []
    for a in angles:
        phi = math.radians(a)
        out.append(form(theta + phi) + dx * math.cos(phi) + dy * math.sin(phi))
    return out


def part(theta):
    return 5.0 + r(theta) + 10.0 * math.cos(theta - 0.3)


def write(name, header, rows, digits=12):
    with open(os.path.join(HERE, name), "w") as f:
        f.write(",".join(header) + "\n")
        for row in rows:
            f.write(",".join(repr(round(v, digits)) for v in row) + "\n")


def main():
    rows = []
    for i in range(N):
        th = 2 * math.pi * i / N
        rows.append(readings(part, th, *spindle(th)))
    write("three_probe.csv", ["A", "B", "C"], rows)

    rows = []
    for i in range(N):
        th = 2 * math.pi * i / N
        rows.append(readings(part, th, *spindle(th), OPPOSITE_DEG))
    write("three_probe_opposite.csv", ["A", "B", "C"], rows)

    rng = random.Random(7)
    rows = []
    for rev in range(8):
        for i in range(N):
            th = 2 * math.pi * i / N
            dx, dy = spindle(th)
            rows.append([y + rng.gauss(0.0, 0.2) for y in readings(part, th, dx, dy, EQUAL_DEG)])
    write("three_probe_noisy.csv", ["A", "B", "C"], rows, digits=4)

    rows = []
    for z in (0.0, 20.0, 40.0, 60.0, 80.0):
        dr, cx, cy = 3 + 0.01 * z, 2 + 0.05 * z, -1 + 0.0005 * z * z
        u, v = 0.3 * math.sin(z / 25), 0.2 * z / 80

        def form(theta, z=z, dr=dr, cx=cx, cy=cy):
            return (dr + (2.0 + 0.01 * z) * math.cos(3 * theta + 0.5) + 0.5 * math.sin(18 * theta)
                    + cx * math.cos(theta) + cy * math.sin(theta))

        for i in range(N):
            th = 2 * math.pi * i / N
            dx, dy = spindle(th)
            rows.append([z] + readings(form, th, dx + u, dy + v))
    write("cylinder_probes.csv", ["z_mm", "A", "B", "C"], rows, digits=10)


if __name__ == "__main__":
    main()
