#!/usr/bin/env python3
"""Writes a camera path (CSV for --path) that walks the streets of a generated city at eye height,
with sharp 90-degree turns at intersections: a staircase of STEP blocks along +x, then STEP
blocks along +z, and so on, each turn done in TURN frames.

  scripts/street_walk.py --city 45x45:4 --frames 400 --out street.csv [--speed 4] [--step 2] [--turn 6]

--city BXxBZ:N matches the scene's city:BXxBZ:N:F:D (blocks and buildings per block side): street
centre lines are at (i - B/2) * pitch, pitch = N * 20 m + 12 m (common/scene/city.hpp)."""
import argparse, math, sys

LOT, STREET = 20.0, 12.0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--city", required=True, help="BXxBZ:N, e.g. 45x45:4")
    ap.add_argument("--frames", type=int, default=400)
    ap.add_argument("--speed", type=float, default=4.0, help="metres per frame")
    ap.add_argument("--step", type=int, default=2, help="blocks between turns")
    ap.add_argument("--turn", type=int, default=6, help="frames per 90-degree turn")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    try:
        bxz, n = a.city.split(":")
        bx, bz = (int(v) for v in bxz.split("x"))
        n = int(n)
    except ValueError:
        sys.exit(f"error: --city '{a.city}': expected BXxBZ:N, e.g. 45x45:4")
    if a.frames < 1 or a.speed <= 0 or a.step < 1 or a.turn < 1:
        sys.exit("error: --frames, --speed, --step and --turn must be positive")
    pitch = n * LOT + STREET
    # Start at the intersection step blocks in from the (-x, -z) corner; walk the diagonal staircase.
    i0 = min(a.step, bx // 2)
    x, z = (i0 - bx / 2) * pitch, (i0 - bz / 2) * pitch
    heading = 0.0  # radians; 0 = +x, pi/2 = +z
    rows = []
    leg_left = a.step * pitch
    turning = 0
    target_heading = heading
    for f in range(a.frames):
        if turning:
            heading += (target_heading - heading) / turning
            turning -= 1
        else:
            step = min(a.speed, leg_left)
            x += step * math.cos(heading)
            z += step * math.sin(heading)
            leg_left -= step
            if leg_left <= 1e-9:  # at an intersection: turn the other way next
                target_heading = math.pi / 2 if heading < math.pi / 4 else 0.0
                turning = a.turn
                leg_left = a.step * pitch
        eye = (x, 1.7, z)
        tgt = (x + math.cos(heading), 1.7, z + math.sin(heading))
        rows.append(f"{f},{eye[0]:.6f},{eye[1]},{eye[2]:.6f},{tgt[0]:.6f},{tgt[1]},{tgt[2]:.6f},0,1,0,60")
    with open(a.out, "w") as out:
        out.write("frame,eye_x,eye_y,eye_z,target_x,target_y,target_z,up_x,up_y,up_z,fovy_deg\n")
        out.write("\n".join(rows) + "\n")


if __name__ == "__main__":
    main()
