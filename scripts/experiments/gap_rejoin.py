# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Poses after a jump over a gap, as written and moved back, against the motion capture.

For each EuRoC recording whose trajectory (TUM files in SRC) has jumps over gaps in its
poses, the trajectory aligned in clock and frame as ``align: auto`` aligns it, against
the recording's motion capture from the first pose (RMS angle): as written (what every
command keeps), and with the poses after each such jump moved into the world before it,
bridged by the gyro as after a jump between blocks (``mask_jumps``).
Usage: .venv/bin/python scripts/experiments/gap_rejoin.py EUROC SRC [SRC ...]
"""

import argparse
from pathlib import Path
import warnings

from denoise_imu_ros.data import pose_alignment
from denoise_imu_ros.data.asl import read_asl
from denoise_imu_ros.data.load import load_recording
from denoise_imu_ros.data.pose_jumps import find_jumps, mask_jumps
from denoise_imu_ros.data.timebase import onto_imu_stamps
import numpy as np
from scipy.spatial.transform import Rotation

RECORDINGS = ('MH_01_easy', 'MH_03_medium', 'MH_05_difficult', 'V1_02_medium', 'V2_01_easy',
              'V2_03_difficult')


def errors_deg(seq, truth) -> float:
    """Return the RMS angle between the poses and the motion capture from the first pose."""
    near = np.searchsorted(truth.stamp_ns, seq.stamp_ns).clip(0, len(truth.stamp_ns) - 1)
    both = seq.gt_valid & truth.gt_valid[near]
    first = np.flatnonzero(both)[0]
    mocap, poses = Rotation.from_quat(truth.gt_quat[near]), Rotation.from_quat(seq.gt_quat)
    error = (mocap[first].inv() * mocap[both]).inv() * (poses[first].inv() * poses[both])
    return float(np.sqrt(np.mean(np.degrees(error.magnitude()) ** 2)))


def main() -> None:
    """Print, per recording with jumps over gaps, the two figures."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument('euroc', type=Path)
    ap.add_argument('sources', type=Path, nargs='+', help='folders of <recording>.txt')
    args = ap.parse_args()
    warnings.simplefilter('ignore')
    for source in args.sources:
        for name in RECORDINGS:
            rec, found, _ = pose_alignment.read_and_align(
                load_recording(args.euroc / name, poses=source))
            seq = onto_imu_stamps(pose_alignment.apply_pose_alignment(
                rec, found['time_offset_s'], found['imu_from_pose_rotation_xyzw']))
            gaps = [j for j in find_jumps(seq) if j.over_gap]
            if not gaps:
                continue
            truth = onto_imu_stamps(read_asl(args.euroc / name))
            moved = mask_jumps(seq, [j._replace(over_gap=False) for j in gaps])
            print(f'{source} {name}: {len(gaps)} over gaps; as written '
                  f'{errors_deg(seq, truth):.1f} deg, moved back {errors_deg(moved, truth):.1f} '
                  'deg', flush=True)


if __name__ == '__main__':
    main()
