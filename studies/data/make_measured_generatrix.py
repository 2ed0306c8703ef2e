#!/usr/bin/env python3
"""Writes studies/data/feed_plan_measured.csv: MODELS.md P3 problem 2's generatrix
y = 30 e^(-x/400) sin((x + 25 pi)/100) + 130 as a measuring machine would report it: every 2 mm
on [0, 600] (301 points) with Gaussian noise of 2 um (seed 20), in mm with 7 decimals.
Used by studies/feed_plan_measured.toml (docs/planner.md, "Measured parts")."""
import math
import os
import random

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    rng = random.Random(20)
    with open(os.path.join(HERE, "feed_plan_measured.csv"), "w") as f:
        f.write("x_mm,y_mm\n")
        for i in range(301):
            x = 2.0 * i
            y = 30 * math.exp(-x / 400) * math.sin((x + 25 * math.pi) / 100) + 130
            f.write(f"{x:.1f},{y + rng.gauss(0.0, 0.002):.7f}\n")


if __name__ == "__main__":
    main()
