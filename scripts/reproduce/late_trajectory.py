# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Recordings' own poses written as a VIO writes them (TUM), starting after the still start.

A VIO initialises in motion: its trajectory starts after the stillness a run starts
with, where the turn-on bias is measured. Each ASL folder of DATA gets OUT/<name>.txt,
its poses from ``--after`` seconds past the first sample whose gyro is more than 10
deg/s from the median of its first 1,000 samples. Give OUT as ``--poses`` or a recipe's
``poses``.
Usage: .venv/bin/python scripts/reproduce/late_trajectory.py DATA OUT [--after 2]
"""

import argparse
from pathlib import Path
import sys

from denoise_imu_ros.data.asl import read_asl
from denoise_imu_ros.data.trajectory import write_tum
import numpy as np

MOVING_RAD_S = np.radians(10.0)


def main() -> None:
    """Write one trajectory file per recording and say where each starts."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument('data', type=Path)
    ap.add_argument('out', type=Path)
    ap.add_argument('--after', type=float, default=2.0)
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    for folder in sorted(p for p in args.data.iterdir() if (p / 'mav0').is_dir()):
        rec = read_asl(folder)
        gyro = rec.imu[:, :3]
        away = np.flatnonzero(np.linalg.norm(gyro - np.median(gyro[:1000], axis=0), axis=1)
                              > MOVING_RAD_S)
        if not len(away):
            sys.exit(f'{folder}: never turns faster than 10 deg/s: no motion to start after')
        moving = int(away[0])
        start = rec.imu_stamp_ns[moving] + int(args.after * 1e9)
        keep = rec.gt_stamp_ns >= start
        write_tum(args.out / f'{folder.name}.txt', rec.gt_stamp_ns[keep], rec.gt_pos[keep],
                  rec.gt_quat[keep])
        first = rec.imu_stamp_ns[0]
        print(f'{folder.name}: moving at {(rec.imu_stamp_ns[moving] - first) * 1e-9:.1f} s, '
              f'poses from {(start - first) * 1e-9:.1f} s')


if __name__ == '__main__':
    main()
