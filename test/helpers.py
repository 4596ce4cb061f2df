# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Writers and builders the tests share: ASL folders, bags, IMU messages, model files.

Imported by the test modules (never from one test module into another); torch and
rclpy are imported only inside the helpers that need them.
"""

import functools
import math
import os
from pathlib import Path

from denoise_imu_ros.core.architecture import ModelConfig
from denoise_imu_ros.core.modelfile import write_model_file
import numpy as np
from rosbags.rosbag1 import Writer as Writer1
from rosbags.typesys import get_typestore, Stores

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / 'shared' / 'data'
SAMPLE = ROOT / 'denoise_imu_ros' / 'sample' / 'euroc_V1_03_90s'
T0 = 1_403_636_579_758_555_648  # a real EuRoC stamp: too big for a float64 parse
ROS1 = get_typestore(Stores.ROS1_NOETIC)
ROS2 = get_typestore(Stores.ROS2_JAZZY)
N = 300  # samples of the synthetic bags
# this test process's own DDS domain: pytest-xdist workers gw0, gw1, ... never share one
_WORKER = os.environ.get('PYTEST_XDIST_WORKER', 'gw0')[2:]
DOMAIN = (int(os.environ.get('ROS_DOMAIN_ID', '42')) + 1 + int(_WORKER or 0)) % 100
# EuRoC-like input normalisation of the untrained test networks
INPUT_MEAN = [0.0, 0.0, 0.0, 9.0, 0.0, -3.0]
INPUT_STD = [0.3, 0.3, 0.3, 1.0, 1.0, 1.0]


def write_asl(root: Path, n_imu=1000, imu_rate=200.0, gt_rate=200.0, gt_offset_s=0.0,
              gt_dir='state_groundtruth_estimate0', yaw_rate=0.3, gt_hole=None, gyro_bias=0.0,
              still_s=0.0, accel=(0.0, 0.0, 9.81)):
    """
    Write a synthetic ASL folder: constant yaw rate (+ z bias), ground truth w,x,y,z.

    ``still_s``: the IMU is still (its gyro the bias alone) for that long first; ``accel``
    its accelerometer reading throughout (level and still: gravity, plus any bias).
    """
    (root / 'mav0' / 'imu0').mkdir(parents=True)
    (root / 'mav0' / gt_dir).mkdir(parents=True)
    t_imu = T0 + np.round(np.arange(n_imu) / imu_rate * 1e9).astype(np.int64)
    with open(root / 'mav0' / 'imu0' / 'data.csv', 'w') as f:
        f.write('#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z\n')
        for t in t_imu:
            turn = yaw_rate if (t - T0) * 1e-9 >= still_s else 0.0
            f.write(f'{t},0.0,0.0,{turn + gyro_bias},{accel[0]},{accel[1]},{accel[2]}\n')
    duration = n_imu / imu_rate
    t_gt = T0 + np.round((gt_offset_s + np.arange(int(duration * gt_rate)) / gt_rate)
                         * 1e9).astype(np.int64)
    if gt_hole is not None:
        rel = (t_gt - T0) * 1e-9
        t_gt = t_gt[(rel < gt_hole[0]) | (rel > gt_hole[1])]
    with open(root / 'mav0' / gt_dir / 'data.csv', 'w') as f:
        f.write('#timestamp, p_x, p_y, p_z, q_w, q_x, q_y, q_z\n')
        for t in t_gt:
            yaw = yaw_rate * max((t - T0) * 1e-9 - still_s, 0.0)
            f.write(f'{t},0.1,0.2,0.3,{math.cos(yaw / 2)},0.0,0.0,{math.sin(yaw / 2)}\n')
    return root


def crop_asl(src: Path, dst: Path, seconds: float) -> Path:
    """Copy an ASL folder's first ``seconds`` of IMU samples and the poses over them."""
    end = None
    for sub in ('imu0', 'state_groundtruth_estimate0', 'mocap0'):
        path = src / 'mav0' / sub / 'data.csv'
        if not path.is_file():
            continue
        lines = path.read_text().splitlines(keepends=True)
        rows = [line for line in lines if not line.startswith('#')]
        if end is None:  # the IMU's: the first folder read
            end = int(rows[0].split(',')[0]) + int(seconds * 1e9)
        (dst / 'mav0' / sub).mkdir(parents=True)
        (dst / 'mav0' / sub / 'data.csv').write_text(''.join(
            [line for line in lines if line.startswith('#')]
            + [line for line in rows if int(line.split(',')[0]) <= end]))
    return dst


def crop_bag(src: Path, dst: Path, seconds: float) -> Path:
    """Copy a rosbag2's first ``seconds`` of messages (received times), every topic and QoS."""
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag2 import StoragePlugin, Writer
    with AnyReader([src]) as reader, Writer(dst, version=9,
                                            storage_plugin=StoragePlugin.MCAP) as writer:
        copy = {c.id: writer.add_connection(
            c.topic, c.msgtype, typestore=reader.typestore,
            offered_qos_profiles=getattr(c.ext, 'offered_qos_profiles', ()))
            for c in reader.connections}
        end = reader.start_time + int(seconds * 1e9)
        for conn, received, raw in reader.messages(stop=end):
            writer.write(copy[conn.id], received, raw)
    return dst


def write_late_trajectory(folder: Path, asl: Path, after_s: float) -> Path:
    """
    Write an ASL folder's poses as a VIO writes them (TUM), from ``after_s`` on.

    A VIO's or a SLAM's trajectory starts after its initialisation, often after the still
    start of the IMU stream.
    """
    from denoise_imu_ros.data.asl import read_asl
    from denoise_imu_ros.data.trajectory import write_tum
    rec = read_asl(asl)
    keep = rec.gt_stamp_ns >= rec.imu_stamp_ns[0] + int(after_s * 1e9)
    write_tum(folder / f'{asl.name}.txt', rec.gt_stamp_ns[keep], rec.gt_pos[keep],
              rec.gt_quat[keep])
    return folder


def shaken_start() -> tuple[np.ndarray, np.ndarray]:
    """Return 10 s at 200 Hz of a still, unbiased gyro, accelerations not gravity alone."""
    rng = np.random.default_rng(0)
    t = np.arange(2000) / 200.0
    gyro = rng.normal(0, 0.002, (len(t), 3))
    accel = np.tile([0.0, 0.0, 9.81], (len(t), 1)) + rng.normal(0, 0.02, (len(t), 3))
    accel[:, 0] += 3.0 * np.sin(2 * np.pi * 0.7 * t)
    accel[:, 1] += 2.0 * np.cos(2 * np.pi * 0.5 * t)
    return gyro, accel


def learnt_on_a_shaken_start(settings) -> float:
    """Return the largest bias (deg/s) an output tracker learns where there is none."""
    from denoise_imu_ros.pipeline.rest_bias import track_bias
    gyro, accel = shaken_start()
    return math.degrees(np.abs(gyro - track_bias(gyro, accel, 200.0, settings)).max())


def break_line(path: Path, line: int, text: str) -> None:
    """Replace one line of a text file (0-based), to damage a CSV."""
    lines = path.read_text().splitlines()
    lines[line] = text
    path.write_text('\n'.join(lines) + '\n')


def bag_messages(ts, pose_type, ros1=False):
    """Yield (topic, msgtype, stamp_ns, message) of a synthetic IMU + pose recording."""
    t = ts.types
    rng = np.random.default_rng(0)
    extra = {'seq': 0} if ros1 else {}

    def header(stamp, frame):
        return t['std_msgs/msg/Header'](stamp=t['builtin_interfaces/msg/Time'](
            sec=stamp // 10**9, nanosec=stamp % 10**9), frame_id=frame, **extra)

    vec = t['geometry_msgs/msg/Vector3']
    quat = t['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=0.6, w=0.8)
    for k in range(N):
        stamp = 1_600_000_000_000_000_000 + k * 5_000_000
        g, a = rng.normal(size=3), rng.normal(size=3)
        yield '/imu0', 'sensor_msgs/msg/Imu', stamp, t['sensor_msgs/msg/Imu'](
            header=header(stamp, 'imu'), orientation=quat, orientation_covariance=np.zeros(9),
            angular_velocity=vec(x=g[0], y=g[1], z=g[2]), angular_velocity_covariance=np.zeros(9),
            linear_acceleration=vec(x=a[0], y=a[1], z=a[2]),
            linear_acceleration_covariance=np.zeros(9))
        if pose_type == 'geometry_msgs/msg/TransformStamped':
            pose = t[pose_type](header=header(stamp, 'world'), child_frame_id='body',
                                transform=t['geometry_msgs/msg/Transform'](
                                    translation=vec(x=1.0, y=2.0, z=float(k)), rotation=quat))
        else:
            p = t['geometry_msgs/msg/Pose'](position=t['geometry_msgs/msg/Point'](
                x=1.0, y=2.0, z=float(k)), orientation=quat)
            cov = t['geometry_msgs/msg/PoseWithCovariance'](pose=p, covariance=np.zeros(36))
            twist = t['geometry_msgs/msg/TwistWithCovariance'](
                twist=t['geometry_msgs/msg/Twist'](linear=vec(x=0.0, y=0.0, z=0.0),
                                                   angular=vec(x=0.0, y=0.0, z=0.0)),
                covariance=np.zeros(36))
            pose = (t[pose_type](header=header(stamp, 'world'), pose=cov)
                    if pose_type.endswith('PoseWithCovarianceStamped') else
                    t[pose_type](header=header(stamp, 'world'), child_frame_id='body',
                                 pose=cov, twist=twist))
        yield '/vicon/body', pose_type, stamp, pose


def write_ros1_bag(path):
    """Write an EuRoC-like ROS 1 bag: Imu and Vicon-style TransformStamped."""
    with Writer1(path) as writer:
        conns = {}
        for topic, msgtype, stamp, msg in bag_messages(
                ROS1, 'geometry_msgs/msg/TransformStamped', ros1=True):
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=ROS1)
            writer.write(conns[topic], stamp, ROS1.serialize_ros1(msg, msgtype))
    return path


def untrained_arrays(config: ModelConfig, seed: int = 0) -> dict[str, np.ndarray]:
    """
    State-dict arrays of an untrained network, drawn as torch initialises one, in numpy.

    Convolutions uniform in +-1/sqrt(fan_in) (torch's default), BatchNorm at identity.
    """
    rng = np.random.default_rng(seed)
    arrays = {}
    for name, shape in config.state_shapes().items():
        if name.endswith('num_batches_tracked'):
            arrays[name] = np.zeros(shape, np.int64)
        elif name.endswith(('running_var', '.weight')) and len(shape) == 1:
            arrays[name] = np.ones(shape, np.float32)  # BatchNorm scale and variance
        elif name.startswith('net.'):
            fan_in = shape[1] * shape[2] if len(shape) == 3 else None
            if fan_in is None:  # BatchNorm shift and mean: 0; conv biases below
                conv = name.replace('.bias', '.weight')
                w = config.state_shapes().get(conv)
                fan_in = w[1] * w[2] if w is not None and len(w) == 3 else None
            bound = 1 / math.sqrt(fan_in) if fan_in else 0.0
            arrays[name] = rng.uniform(-bound, bound, shape).astype(np.float32)
        else:
            arrays[name] = np.zeros(shape, np.float32)
    arrays.update(input_mean=np.array(INPUT_MEAN, np.float32),
                  input_std=np.array(INPUT_STD, np.float32),
                  gyro_std=np.array(config.gyro_std, np.float32))
    return arrays


def write_untrained_model(path: Path, meta: dict | None = None, seed: int = 0,
                          **config) -> Path:
    """Write an untrained model file with numpy alone (no torch)."""
    cfg = ModelConfig(**config)
    write_model_file(path, cfg, untrained_arrays(cfg, seed), meta or {})
    return path


def untrained_model(**config):
    """Build a seeded, untrained eval-mode torch network with EuRoC-like normalisation."""
    from denoise_imu_ros.learn.model import GyroNet
    import torch
    torch.manual_seed(0)
    model = GyroNet(ModelConfig(**config))
    model.set_normalization(torch.tensor(INPUT_MEAN), torch.tensor(INPUT_STD))
    return model.eval()


def imu_msg(stamp_ns, gyro, accel, frame='imu4'):
    """Build a sensor_msgs/Imu as a driver would."""
    from builtin_interfaces.msg import Time
    from sensor_msgs.msg import Imu
    msg = Imu()
    msg.header.stamp = Time(sec=int(stamp_ns // 10**9), nanosec=int(stamp_ns % 10**9))
    msg.header.frame_id = frame
    (msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z) = map(float, gyro)
    (msg.linear_acceleration.x, msg.linear_acceleration.y,
     msg.linear_acceleration.z) = map(float, accel)
    msg.linear_acceleration_covariance[0] = 0.04
    return msg


@functools.cache
def _sample_cdr() -> tuple[bytes, ...]:
    """Return the bundled sample bag's IMU messages as serialised, read once per process."""
    from denoise_imu_ros.data.bags import IMU_TYPE, open_bag, pick_connections
    with open_bag(SAMPLE) as reader:
        conns = pick_connections(reader, None, (IMU_TYPE,), 'IMU', SAMPLE)
        return tuple(bytes(raw) for _, _, raw in reader.messages(connections=conns))


def sample_messages(n: int) -> list:
    """
    Return the sample bag's first n IMU messages as rclpy messages, new ones at every call.

    Equal to ``read_imu_messages(SAMPLE)[:n]`` (test_player checks it), without
    deserialising the whole bag for each test that plays its head.
    """
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import Imu
    return [deserialize_message(raw, Imu) for raw in _sample_cdr()[:n]]
