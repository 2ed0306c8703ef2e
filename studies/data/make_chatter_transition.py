#!/usr/bin/env python3
"""Writes chatter_transition.csv, the signal of studies/chatter_monitor_transition.toml.

A synthetic stable -> chatter transition of a grinding vibration signal (MODELS.md C3): 1 s at
8 kHz of white Gaussian noise (rms 0.1 um, the stable process), plus from t = 0.5 s a 360 Hz sine
with random phase whose amplitude grows exponentially at 25 /s from 0.005 um and saturates at
0.8 um (logistic law, as chatter limited by loss of contact):
    a(t) = a_sat / (1 + (a_sat / a0 - 1) exp(-g (t - 0.5)))
The sine amplitude passes the noise rms at t = 0.625 s. Columns t_s, displacement_m: the layout of
a `simulate` study's timeseries.csv. Python standard library only; fixed seed, so the file is
reproducible:  python3 make_chatter_transition.py > chatter_transition.csv
"""
import math
import random
import sys

RATE_HZ, DURATION_S = 8000, 1.0
NOISE_RMS_M = 1e-7
ONSET_S, FREQUENCY_HZ = 0.5, 360.0
A0_M, GROWTH_PER_S, A_SAT_M = 5e-9, 25.0, 8e-7


def amplitude(t):
    if t < ONSET_S:
        return 0.0
    return A_SAT_M / (1.0 + (A_SAT_M / A0_M - 1.0) * math.exp(-GROWTH_PER_S * (t - ONSET_S)))


def main():
    rng = random.Random(20261121)
    phase = rng.uniform(0.0, 2.0 * math.pi)
    out = sys.stdout
    out.write("t_s,displacement_m\n")
    for i in range(int(RATE_HZ * DURATION_S)):
        t = i / RATE_HZ
        x = NOISE_RMS_M * rng.gauss(0.0, 1.0) + amplitude(t) * math.sin(
            2.0 * math.pi * FREQUENCY_HZ * t + phase)
        out.write(f"{t:.6f},{x:.6g}\n")


if __name__ == "__main__":
    main()
