#!/usr/bin/env python3
"""Writes g8_tap_test.uff, the synthetic tap test of studies/default.toml (deterministic, seed 1).

What an impact-hammer test at the wheel-work contact of the MODELS.md G8 grinder (M1432) would
give, in the Universal File Format: dataset 164 (SI units) and dataset 58 (ASCII, even
abscissa), accelerance A = X''/F in (m/s^2)/N from 10 to 500 Hz every 0.25 Hz (1961 lines, a
4 s record), drive point (response and reference both node 1, +X).

The structure is the seven measured machine modes of G8 (book table 3-2: 67.56 ... 305.60 Hz)
with the stiffnesses of the equal-modal-mass assumption of the G8 studies (total
static stiffness 30 N/um, m = 307 kg; studies/default.toml explains them) and 3 %
damping: receptance H(j w) = sum_i (1/k_i) / (1 - r_i^2 + 2 j zeta_i r_i), r_i = f/f_i, sign
convention e^{+j w t}, A = -w^2 H. Each line is multiplied by (1 + 0.02 (n_re + j n_im)) with
n standard normal (2 % complex noise, Python's random.gauss, seed 1).
"""
import math
import random

MODES = [  # frequency [Hz], damping ratio, modal stiffness [N/m]
    (67.56, 0.03, 5.53e7), (102.44, 0.03, 1.27e8), (184.08, 0.03, 4.11e8), (221.11, 0.03, 5.93e8),
    (255.01, 0.03, 7.88e8), (275.05, 0.03, 9.17e8), (305.60, 0.03, 1.132e9),
]
F0, DF, LINES, NOISE = 10.0, 0.25, 1961, 0.02

random.seed(1)
values = []
for i in range(LINES):
    f = F0 + i * DF
    h = sum(1.0 / (k * complex(1.0 - (f / fn) ** 2, 2.0 * z * f / fn)) for fn, z, k in MODES)
    h *= complex(1.0 + NOISE * random.gauss(0.0, 1.0), NOISE * random.gauss(0.0, 1.0))
    a = -(2.0 * math.pi * f) ** 2 * h
    values += [a.real, a.imag]

def e13(v):
    return f"{v:13.5E}"

out = [f"{-1:>6}", f"{164:>6}", f"{1:>10}{'SI':<20}{2:>10}",
       f"{1.0:25.16E}{1.0:25.16E}{1.0:25.16E}", f"{273.15:25.16E}", f"{-1:>6}",
       f"{-1:>6}", f"{58:>6}",
       f"{'G8 grinder, synthetic tap test at the wheel-work contact':<80}",
       f"{'seven G8 modes, 3 % damping, 2 % complex noise, seed 1':<80}", f"{'NONE':<80}",
       f"{'NONE':<80}", f"{'NONE':<80}",
       f"{4:>5}{1:>10}{1:>5}{0:>10} {'NONE':<10}{1:>10}{1:>4} {'NONE':<10}{1:>10}{1:>4}",
       f"{6:>10}{LINES:>10}{1:>10}{e13(F0)}{e13(DF)}{e13(0.0)}",
       f"{18:>10}{0:>5}{0:>5}{0:>5} {'Frequency':<20} {'Hz':<20}",
       f"{12:>10}{1:>5}{0:>5}{0:>5} {'accelerance':<20} {'m/s^2':<20}",
       f"{13:>10}{0:>5}{1:>5}{0:>5} {'Force':<20} {'N':<20}",
       f"{0:>10}{0:>5}{0:>5}{0:>5} {'NONE':<20} {'NONE':<20}"]
for i in range(0, len(values), 4):
    out.append("".join(f"{v:20.11E}" for v in values[i:i + 4]))
out.append(f"{-1:>6}")
with open("g8_tap_test.uff", "w") as f:
    f.write("\n".join(out) + "\n")
