#!/usr/bin/env python3
"""Writes the synthetic example profiles of studies/surface_*.toml (deterministic, seed 1).

surface_g8_roundness.csv: one revolution of a ground part (MODELS.md G8: n_g = 1450 rpm,
  n_w = 55 rpm, so Z = 26.4 wheel revolutions per work revolution), 7200 samples, radial
  deviation in um: eccentricity 4 um, ovality 0.8 um, 26 forced lobes of amplitude 2.13 um
  (Wz 4.26 um, the book's low band), a chatter band at 895 lobes (820 Hz at 55 rpm) of
  amplitude 1.56 um (Wz 3.12 um, the book's high band) with weak 893/897 sidebands, and 0.03 um
  rms roughness noise.
surface_open_profile.csv: 8 mm axial profile at 2 um spacing, height in um: tilt, a 1.6 mm
  waviness of amplitude 1.5 um, a 0.4 mm waviness of 0.5 um, roughness of 0.25 um rms
  (wavelengths 15-60 um).
"""
import math
import random

random.seed(1)
n = 7200
with open("surface_g8_roundness.csv", "w") as f:
    f.write("radius_um\n")
    for i in range(n):
        th = 2 * math.pi * i / n
        r = (4.0 * math.cos(th - 0.7) + 0.8 * math.cos(2 * th + 0.3)
             + 2.13 * math.cos(26 * th + 1.1)
             + 1.56 * math.cos(895 * th) + 0.04 * math.cos(893 * th + 0.5)
             + 0.04 * math.cos(897 * th + 2.0) + random.gauss(0.0, 0.03))
        f.write(f"{r:.4f}\n")

dx = 0.002
# Roughness: 40 random sines of wavelengths 15-60 um (a ground surface's grit marks are not white
# noise at the sampling step), 0.25 um rms in total.
grit = [(random.uniform(0.015, 0.06), random.uniform(0, 2 * math.pi)) for _ in range(40)]
amp = 0.25 * math.sqrt(2.0 / len(grit))
with open("surface_open_profile.csv", "w") as f:
    f.write("x_mm,height_um\n")
    for i in range(4001):
        x = i * dx
        z = (0.3 * x + 1.5 * math.sin(2 * math.pi * x / 1.6) + 0.5 * math.sin(2 * math.pi * x / 0.4 + 1)
             + sum(amp * math.sin(2 * math.pi * x / lam + ph) for lam, ph in grit))
        f.write(f"{x:.3f},{z:.4f}\n")
