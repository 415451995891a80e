#!/usr/bin/env python3
"""Writes the evemu recording of a mouse sweeping across the embedded default scene's three targets.

Frames every 8 ms (a 125 Hz mouse); each leg follows a minimum-jerk profile (the bell-shaped speed of a
hand's reach), its counts rounded with the remainder carried so that the legs add up exactly. Started at
the centre of the 1920 x 1080 desktop: 1300 counts left (across the hole and the Gaussian bump), 2600
right (across all three targets), 1300 left; a slight vertical wave keeps it off the targets' middle row.
Where a target slows the cursor it travels fewer pixels, so it does not come back to where it started.

    tools/sweep_recording.py > data/recordings/sweep-default-scene.evemu
"""
import argparse
import math

FRAME_US = 8000
LEGS = [(-1300, 1.8), (2600, 3.6), (-1300, 1.8)]  # (dx in counts, seconds)

HEADER = """# EVEMU 1.3
# A mouse sweeping across the three targets of pseudohaptic's embedded default scene, made by
# tools/sweep_recording.py (minimum-jerk legs at 125 Hz): 1300 counts left, 2600 right, 1300 left.
# Input device name: "pseudohaptic sweep mouse"
# Input device ID: bus 0x03 vendor 0x0000 product 0x0000 version 0000
N: pseudohaptic sweep mouse
I: 0003 0000 0000 0000
P: 00 00 00 00 00 00 00 00
B: 00 07 00 00 00 00 00 00 00
B: 01 00 00 00 00 00 00 00 00
B: 01 00 00 00 00 00 00 00 00
B: 01 00 00 00 00 00 00 00 00
B: 01 00 00 00 00 00 00 00 00
B: 01 00 00 07 00 00 00 00 00
B: 01 00 00 00 00 00 00 00 00
B: 01 00 00 00 00 00 00 00 00
B: 01 00 00 00 00 00 00 00 00
B: 01 00 00 00 00 00 00 00 00
B: 01 00 00 00 00 00 00 00 00
B: 01 00 00 00 00 00 00 00 00
B: 01 00 00 00 00 00 00 00 00
B: 02 03 01 00 00 00 00 00 00
B: 03 00 00 00 00 00 00 00 00
B: 04 00 00 00 00 00 00 00 00
B: 05 00 00 00 00 00 00 00 00
B: 11 00 00 00 00 00 00 00 00
B: 12 00 00 00 00 00 00 00 00
B: 15 00 00 00 00 00 00 00 00
B: 15 00 00 00 00 00 00 00 00"""


def min_jerk(s):
    return 10 * s**3 - 15 * s**4 + 6 * s**5


def main():
    argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter).parse_args()
    print(HEADER)
    t = 1  # microseconds
    x = y = 0.0  # exact position, counts
    ex = ey = 0  # emitted
    frame = 0
    for dx, seconds in LEGS:
        steps = round(seconds * 1e6 / FRAME_US)
        x0 = x
        for i in range(1, steps + 1):
            frame += 1
            x = x0 + dx * min_jerk(i / steps)
            y = 40 * math.sin(frame * FRAME_US / 1e6 * 1.3)
            rx, ry = round(x) - ex, round(y) - ey
            ex, ey = ex + rx, ey + ry
            t += FRAME_US
            stamp = f"{t // 1000000}.{t % 1000000:06d}"
            if rx:
                print(f"E: {stamp} 0002 0000 {rx}")
            if ry:
                print(f"E: {stamp} 0002 0001 {ry}")
            if rx or ry:
                print(f"E: {stamp} 0000 0000 0000")


main()
