# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
A VIO's trajectories as other tools write them and as ROS users record them.

From a folder of TUM files (``<recording>.txt``) and the ASL folders of the same
recordings, one folder per kind under OUT:
- ``vins_fusion``: ``<recording>.csv`` as VINS-Mono's and VINS-Fusion's own writer formats
  it (``t[ns],x,y,z,qw,qx,qy,qz,vx,vy,vz,``: five decimals, a trailing comma; the velocity
  written as 0, it is not read);
- ``orb_slam3``: ``<recording>.txt`` as ORB-SLAM3 writes EuRoC's (nanoseconds, spaces);
- ``odometry``: ROS 2 bags (MCAP) of the recording's IMU on ``/imu0`` and the poses as
  ``nav_msgs/Odometry`` on ``/vins_estimator/odometry`` and ``/vins_estimator/camera_pose``,
  each logged LATENCY_NS after its stamp, as a VIO publishes after its image;
- ``pose_with_covariance``: the same with one ``PoseWithCovarianceStamped`` topic,
  ``/ov_msckf/poseimu`` (OpenVINS's).
Usage: .venv/bin/python scripts/experiments/vio_outputs.py SRC ASL OUT RECORDING...
"""

import argparse
from pathlib import Path
from typing import Any

from denoise_imu_ros.core import msgs
from denoise_imu_ros.data.asl import read_asl
from denoise_imu_ros.data.bags import BAG_TYPES, imu_message, IMU_TYPE, TYPESTORE
from denoise_imu_ros.data.trajectory import read_tum, Trajectory
import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer

LATENCY_NS = 30_000_000
ODOMETRY = 'nav_msgs/msg/Odometry'
WITH_COVARIANCE = 'geometry_msgs/msg/PoseWithCovarianceStamped'
TOPICS = {'odometry': [('/vins_estimator/odometry', ODOMETRY),
                       ('/vins_estimator/camera_pose', ODOMETRY)],
          'pose_with_covariance': [('/ov_msckf/poseimu', WITH_COVARIANCE)]}


def text_files(trajectory: Trajectory, name: str, out: Path) -> None:
    """Write the trajectory as VINS-Fusion's CSV and as ORB-SLAM3's EuRoC file."""
    csv, spaced = [], []
    for t, (x, y, z), (qx, qy, qz, qw) in zip(trajectory.stamp_ns.tolist(),
                                              trajectory.pos.tolist(), trajectory.quat.tolist()):
        csv.append(f'{t},{x:.5f},{y:.5f},{z:.5f},{qw:.5f},{qx:.5f},{qy:.5f},{qz:.5f},'
                   '0.00000,0.00000,0.00000,\n')
        spaced.append(f'{t} {x:.9f} {y:.9f} {z:.9f} {qx:.9f} {qy:.9f} {qz:.9f} {qw:.9f}\n')
    for kind, suffix, lines in (('vins_fusion', '.csv', csv), ('orb_slam3', '.txt', spaced)):
        (out / kind).mkdir(parents=True, exist_ok=True)
        (out / kind / f'{name}{suffix}').write_text(''.join(lines))


def pose_message(msgtype: str, stamp: int, pos: np.ndarray, quat: np.ndarray) -> Any:
    """Return an ``Odometry`` or a ``PoseWithCovarianceStamped`` holding one pose."""
    t = TYPESTORE.types
    vector = t['geometry_msgs/msg/Vector3']
    pose = t['geometry_msgs/msg/PoseWithCovariance'](
        pose=t['geometry_msgs/msg/Pose'](
            position=t['geometry_msgs/msg/Point'](*pos),
            orientation=t['geometry_msgs/msg/Quaternion'](*quat)),
        covariance=np.zeros(36))
    header = msgs.header(BAG_TYPES, stamp, 'world')
    if msgtype == WITH_COVARIANCE:
        return t[msgtype](header=header, pose=pose)
    still = t['geometry_msgs/msg/Twist'](linear=vector(0.0, 0.0, 0.0),
                                         angular=vector(0.0, 0.0, 0.0))
    return t[msgtype](header=header, child_frame_id='body', pose=pose,
                      twist=t['geometry_msgs/msg/TwistWithCovariance'](
                          twist=still, covariance=np.zeros(36)))


def bag(asl: Path, trajectory: Trajectory, kind: str, out: Path) -> None:
    """Write the recording's IMU and the trajectory's poses as a VIO's run is recorded."""
    rec = read_asl(asl, with_gt=False)
    (out / kind).mkdir(parents=True, exist_ok=True)
    with Writer(out / kind / asl.name, version=9, storage_plugin=StoragePlugin.MCAP) as w:
        imu = w.add_connection('/imu0', IMU_TYPE, typestore=TYPESTORE)
        poses = [(w.add_connection(topic, msgtype, typestore=TYPESTORE), msgtype)
                 for topic, msgtype in TOPICS[kind]]
        events = sorted([(int(s), 0, i) for i, s in enumerate(rec.imu_stamp_ns)]
                        + [(int(s) + LATENCY_NS, 1, i)
                           for i, s in enumerate(trajectory.stamp_ns)])
        for logged, what, i in events:
            if what == 0:
                stamp, row = int(rec.imu_stamp_ns[i]), rec.imu[i]
                w.write(imu, logged, TYPESTORE.serialize_cdr(
                    imu_message(stamp, row[:3], row[3:]), IMU_TYPE))
                continue
            for conn, msgtype in poses:
                msg = pose_message(msgtype, int(trajectory.stamp_ns[i]), trajectory.pos[i],
                                   trajectory.quat[i])
                w.write(conn, logged, TYPESTORE.serialize_cdr(msg, msgtype))


def main() -> None:
    """Write every kind of every recording's trajectory under OUT/<kind>/."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    ap.add_argument('src', type=Path, help='folder of <recording>.txt (TUM)')
    ap.add_argument('asl', type=Path, help='folder of the recordings (ASL)')
    ap.add_argument('out', type=Path)
    ap.add_argument('recordings', nargs='+')
    args = ap.parse_args()
    for name in args.recordings:
        trajectory = read_tum(args.src / f'{name}.txt')
        text_files(trajectory, name, args.out)
        for kind in TOPICS:
            bag(args.asl / name, trajectory, kind, args.out)
    print(f'written under {args.out}')


if __name__ == '__main__':
    main()
