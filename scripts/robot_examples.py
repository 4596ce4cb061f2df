# Copyright 2026 denoise_imu_ros authors
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.
"""
Robot-like bags made from EuRoC and TUM-VI, for the "Train on your robot" example.

Each is a ROS 2 bag with a robot's topic names (``/imu/data_raw`` and a pose topic),
written from a real recording with one thing changed, the way a robot's data differs
from a benchmark's:
- ``tumvi``: TUM-VI rooms as recorded (~200 Hz IMU, 120 Hz mocap with its holes) on
  ``/imu/data_raw`` and ``/mocap/pose``;
- ``euroc100``: EuRoC at 100 Hz (each pair of samples and stamps averaged) with the
  poses thinned to 20 Hz, like a VIO trajectory, on ``/imu/data_raw`` and ``/vio/pose``;
- ``move``: the poses of a marker body (rotated, with a lever arm) on a clock shifted by
  an offset, ``t_imu = t_pose + offset``: what check-data and ``align: auto`` undo.

Usage: .venv/bin/python scripts/robot_examples.py {tumvi,euroc100,move} DATA OUT
           [--sequences S ...] [--offset-ms MS --rotvec-deg X Y Z --lever-m X Y Z]
"""

import argparse
import dataclasses
from pathlib import Path

from denoise_imu_ros.bags import write_bag
from denoise_imu_ros.dataset import read_asl
from denoise_imu_ros.records import Recording
import numpy as np
from scipy.spatial.transform import Rotation

IMU_TOPIC = '/imu/data_raw'


def halve_rate(rec: Recording) -> Recording:
    """Average each pair of IMU samples and stamps (the rate at the pair's mid-stamp)."""
    n = len(rec.imu_stamp_ns) // 2 * 2
    imu = rec.imu[:n].reshape(-1, 2, 6).mean(axis=1)
    stamps = rec.imu_stamp_ns[:n].reshape(-1, 2).mean(axis=1).round().astype(np.int64)
    return dataclasses.replace(rec, imu_stamp_ns=stamps, imu=imu)


def thin_poses(rec: Recording, rate_hz: float) -> Recording:
    """Keep each pose 0.95 / rate_hz or more after the last kept (all, if at that rate)."""
    keep, last = [], None
    for i, t in enumerate(rec.gt_stamp_ns):
        if last is None or t - last >= 0.95e9 / rate_hz:
            keep.append(i)
            last = t
    return dataclasses.replace(rec, gt_stamp_ns=rec.gt_stamp_ns[keep],
                               gt_quat=rec.gt_quat[keep], gt_pos=rec.gt_pos[keep])


def move_poses(rec: Recording, offset_s: float, imu_from_pose: Rotation,
               lever_m: np.ndarray) -> Recording:
    """
    Return the poses of another body, on another clock.

    The body sits at ``lever_m`` from the IMU (in the IMU frame), rotated so that
    ``omega_imu = imu_from_pose * omega_pose``; its poses are stamped ``offset_s`` early.
    """
    body = Rotation.from_quat(rec.gt_quat)
    return dataclasses.replace(
        rec, gt_stamp_ns=rec.gt_stamp_ns - round(offset_s * 1e9),
        gt_quat=(body * imu_from_pose).as_quat(), gt_pos=rec.gt_pos + body.apply(lever_m))


def main() -> None:
    """Write one bag per sequence of DATA into OUT."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('kind', choices=('tumvi', 'euroc100', 'move'))
    parser.add_argument('data', type=Path, help='folder of ASL sequences')
    parser.add_argument('out', type=Path, help='folder to write the bags into')
    parser.add_argument('--sequences', nargs='+', help='default: every sequence in DATA')
    parser.add_argument('--offset-ms', type=float, default=37.3)
    parser.add_argument('--rotvec-deg', type=float, nargs=3, default=(30.0, -20.0, 45.0))
    parser.add_argument('--lever-m', type=float, nargs=3, default=(0.12, 0.0, 0.05))
    args = parser.parse_args()
    names = args.sequences or sorted(p.name for p in args.data.iterdir() if p.is_dir())
    args.out.mkdir(parents=True, exist_ok=True)
    for name in names:
        rec = read_asl(args.data / name)
        pose_topic = '/mocap/pose'
        if args.kind == 'euroc100':
            rec, pose_topic = thin_poses(halve_rate(rec), 20.0), '/vio/pose'
        elif args.kind == 'move':
            rec = move_poses(rec, args.offset_ms * 1e-3,
                             Rotation.from_rotvec(args.rotvec_deg, degrees=True),
                             np.array(args.lever_m))
        write_bag(rec, args.out / name, imu_topic=IMU_TOPIC, pose_topic=pose_topic)
        print(f'{args.out / name}: {len(rec.imu)} IMU samples on {IMU_TOPIC}, '
              f'{len(rec.gt_quat)} poses on {pose_topic}')


if __name__ == '__main__':
    main()
