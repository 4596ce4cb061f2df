# Copyright 2026 denoise_imu_ros authors
# Licensed under the Apache License, Version 2.0
"""Bags through rosbags: convert round trip, ROS 1 and ROS 2 inputs, topic errors."""

from pathlib import Path

from denoise_imu_ros.cli import main
from denoise_imu_ros.dataset import load_sequence
from denoise_imu_ros.errors import DatasetError
from denoise_imu_ros.train import load_config, training_split
import numpy as np
import pytest
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import Writer as Writer2
from rosbags.typesys import get_typestore, Stores
import torch

ROS1 = get_typestore(Stores.ROS1_NOETIC)
ROS2 = get_typestore(Stores.ROS2_JAZZY)
N = 300


def _msgs(ts, pose_type, ros1=False):
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
            pose = t[pose_type](header=header(stamp, 'world'), child_frame_id='body',
                                pose=cov, twist=twist)
        yield '/vicon/body', pose_type, stamp, pose


def _check(seq):
    assert len(seq) == N
    np.testing.assert_allclose(seq.gt_quat[0], [0.0, 0.0, 0.6, 0.8])
    np.testing.assert_allclose(seq.gt_pos[:, 2], np.arange(N))
    assert np.all(np.diff(seq.stamp_ns) == 5_000_000)


def _write_ros1(path):
    """Write an EuRoC-like ROS 1 bag: Imu and Vicon-style TransformStamped."""
    with Writer1(path) as writer:
        conns = {}
        for topic, msgtype, stamp, msg in _msgs(ROS1, 'geometry_msgs/msg/TransformStamped',
                                                ros1=True):
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=ROS1)
            writer.write(conns[topic], stamp, ROS1.serialize_ros1(msg, msgtype))
    return path


def test_ros1_bag_with_transform_stamped_ground_truth(tmp_path):
    _check(load_sequence(_write_ros1(tmp_path / 'euroc_like.bag')))


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_ros2_bag_with_odometry_ground_truth_and_explicit_topics(tmp_path, storage):
    from rosbags.rosbag2 import StoragePlugin
    path = tmp_path / 'odom'
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    with Writer2(path, version=9, storage_plugin=plugin) as writer:
        conns = {}
        for topic, msgtype, stamp, msg in _msgs(ROS2, 'nav_msgs/msg/Odometry'):
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=ROS2)
            writer.write(conns[topic], stamp, ROS2.serialize_cdr(msg, msgtype))
    _check(load_sequence(path, imu_topic='imu0', pose_topic='/vicon/body'))
    with pytest.raises(DatasetError, match=r"no topic '/imu9' \(topics: /imu0 \["):
        load_sequence(path, imu_topic='/imu9')
    with pytest.raises(DatasetError, match="topic '/imu0' has type sensor_msgs/msg/Imu, "
                                           'expected geometry_msgs'):
        load_sequence(path, pose_topic='/imu0')


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_training_arrays_from_converted_bag_equal_those_from_csv(euroc, tmp_path, storage):
    seq_dir = euroc / 'V1_02_medium'
    bag = tmp_path / f'V1_02_medium_{storage}'
    assert main(['convert', str(seq_dir), str(bag), '--storage', storage]) == 0
    cfg = load_config(Path(__file__).parents[1] / 'config' / 'train_euroc.yaml')
    from_csv = training_split([load_sequence(seq_dir)], cfg)
    from_bag = training_split([load_sequence(bag)], cfg)
    for name in ('imu', 'dt', 'quat', 'valid'):
        assert torch.equal(getattr(from_csv, name), getattr(from_bag, name)), name
    a, b = load_sequence(seq_dir), load_sequence(bag)
    assert np.array_equal(a.stamp_ns, b.stamp_ns) and np.array_equal(a.gt_pos, b.gt_pos)


def test_convert_refuses_an_existing_output(euroc, tmp_path, capsys):
    (tmp_path / 'out').mkdir()
    assert main(['convert', str(euroc / 'V1_02_medium'), str(tmp_path / 'out')]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith('denoise-imu convert: error:') and str(tmp_path / 'out') in err
    assert '\n' not in err


def test_convert_overlap_keeps_only_the_span_with_ground_truth(euroc, tmp_path):
    from denoise_imu_ros.dataset import read_asl
    from denoise_imu_ros.bags import read_bag
    # V1_02's ground truth starts ~1 s after its IMU (V1_01's corrected one does not).
    seq = euroc / 'V1_02_medium'
    assert main(['convert', str(seq), str(tmp_path / 'b'), '--overlap']) == 0
    rec, asl = read_bag(tmp_path / 'b'), read_asl(seq)
    assert asl.gt_stamp_ns[0] > asl.imu_stamp_ns[0]  # the case this test is about
    assert rec.imu_stamp_ns[0] >= asl.gt_stamp_ns[0]
    assert len(load_sequence(tmp_path / 'b')) == len(load_sequence(seq))


def test_convert_writes_the_topic_names_asked_for(tmp_path):
    from denoise_imu_ros.bags import read_bag
    from test_dataset import write_asl
    seq = write_asl(tmp_path / 'a', n_imu=600)
    assert main(['convert', str(seq), str(tmp_path / 'b'), '--imu-topic', '/imu/data_raw',
                 '--pose-topic', '/mocap/pose']) == 0
    with pytest.raises(DatasetError, match=r"no topic '/imu0' \(topics: /imu/data_raw"):
        read_bag(tmp_path / 'b', imu_topic='/imu0')
    rec = read_bag(tmp_path / 'b', imu_topic='/imu/data_raw', pose_topic='/mocap/pose')
    assert len(rec.imu) == 600
