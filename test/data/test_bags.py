# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Bags through rosbags: convert round trip, ROS 1 and ROS 2 inputs, topic errors."""

from denoise_imu_ros.cli import main
from denoise_imu_ros.core.errors import DatasetError
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.learn.config import load_config
from denoise_imu_ros.learn.train import training_split
from helpers import bag_messages, N, ROOT, ROS2, write_ros1_bag
import numpy as np
import pytest
from rosbags.rosbag2 import Writer as Writer2
import torch


def _check(seq):
    assert len(seq) == N
    np.testing.assert_allclose(seq.gt_quat[0], [0.0, 0.0, 0.6, 0.8])
    np.testing.assert_allclose(seq.gt_pos[:, 2], np.arange(N))
    assert np.all(np.diff(seq.stamp_ns) == 5_000_000)


def test_ros1_bag_with_transform_stamped_ground_truth(tmp_path):
    _check(load_sequence(write_ros1_bag(tmp_path / 'euroc_like.bag')))


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_ros2_bag_with_odometry_ground_truth_and_explicit_topics(tmp_path, storage):
    from rosbags.rosbag2 import StoragePlugin
    path = tmp_path / 'odom'
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    with Writer2(path, version=9, storage_plugin=plugin) as writer:
        conns = {}
        for topic, msgtype, stamp, msg in bag_messages(ROS2, 'nav_msgs/msg/Odometry'):
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
    cfg = load_config(ROOT / 'config' / 'train_euroc.yaml')
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
    from denoise_imu_ros.data.asl import read_asl
    from denoise_imu_ros.data.bags import read_bag
    # V1_02's ground truth starts ~1 s after its IMU (V1_01's corrected one does not).
    seq = euroc / 'V1_02_medium'
    assert main(['convert', str(seq), str(tmp_path / 'b'), '--overlap']) == 0
    rec, asl = read_bag(tmp_path / 'b'), read_asl(seq)
    assert asl.gt_stamp_ns[0] > asl.imu_stamp_ns[0]  # the case this test is about
    assert rec.imu_stamp_ns[0] >= asl.gt_stamp_ns[0]
    assert len(load_sequence(tmp_path / 'b')) == len(load_sequence(seq))


def test_convert_writes_the_topic_names_asked_for(tmp_path):
    from denoise_imu_ros.data.bags import read_bag
    from helpers import write_asl
    seq = write_asl(tmp_path / 'a', n_imu=600)
    assert main(['convert', str(seq), str(tmp_path / 'b'), '--imu-topic', '/imu/data_raw',
                 '--pose-topic', '/mocap/pose']) == 0
    with pytest.raises(DatasetError, match=r"no topic '/imu0' \(topics: /imu/data_raw"):
        read_bag(tmp_path / 'b', imu_topic='/imu0')
    rec = read_bag(tmp_path / 'b', imu_topic='/imu/data_raw', pose_topic='/mocap/pose')
    assert len(rec.imu) == 600


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_a_bag_compressed_inside_its_mcap_chunks_is_seen_as_compressed(tmp_path, storage):
    """MCAP storage compression leaves metadata.yaml's mode empty."""
    from denoise_imu_ros.data.bags import is_compressed, open_bag
    from helpers import write_asl
    rec = write_asl(tmp_path / 'rec', n_imu=400)
    for compress in (True, False):
        out = tmp_path / f'{storage}_{compress}'
        argv = ['convert', str(rec), str(out), '--storage', storage]
        assert main(argv + ['--compress'] * compress) == 0
        with open_bag(out) as reader:
            assert is_compressed(reader) == compress


def test_every_reader_takes_a_bag_in_header_stamp_order(tmp_path):
    """1-15 ms of transport latency reorders the receive order."""
    from denoise_imu_ros.core import msgs
    from denoise_imu_ros.data.asl import read_asl
    from denoise_imu_ros.data.bags import (BAG_TYPES, imu_message, IMU_TYPE, POSE_TYPES,
                                           read_bag, TYPESTORE)
    from helpers import write_asl
    rec = read_asl(write_asl(tmp_path / 'asl', n_imu=1200))
    rng = np.random.default_rng(0)
    t = TYPESTORE.types
    items = []
    with Writer2(tmp_path / 'jittered', version=9) as w:
        imu = w.add_connection('/imu0', IMU_TYPE, typestore=TYPESTORE)
        pose = w.add_connection('/pose', POSE_TYPES[0], typestore=TYPESTORE)
        for stamp, row in zip(rec.imu_stamp_ns, rec.imu):
            items.append((int(stamp) + int(rng.uniform(1e6, 15e6)), int(stamp), imu,
                          TYPESTORE.serialize_cdr(imu_message(int(stamp), row[:3], row[3:]),
                                                  IMU_TYPE)))
        for stamp, q, p in zip(rec.gt_stamp_ns, rec.gt_quat, rec.gt_pos):
            msg = t[POSE_TYPES[0]](header=msgs.header(BAG_TYPES, int(stamp), 'world'), pose=t[
                'geometry_msgs/msg/Pose'](position=t['geometry_msgs/msg/Point'](*p),
                                          orientation=t['geometry_msgs/msg/Quaternion'](*q)))
            items.append((int(stamp) + int(rng.uniform(1e6, 15e6)), int(stamp), pose,
                          TYPESTORE.serialize_cdr(msg, POSE_TYPES[0])))
        items.sort(key=lambda item: item[0])
        for receive, _, conn, raw in items:
            w.write(conn, receive, raw)
    got = read_bag(tmp_path / 'jittered')
    received = [stamp for _, stamp, conn, _ in items if conn is imu]
    assert (np.diff(received) < 0).sum() > 100  # the receive order is not the stamps'
    for field in ('imu_stamp_ns', 'imu', 'gt_stamp_ns', 'gt_quat', 'gt_pos'):
        np.testing.assert_array_equal(getattr(got, field), getattr(rec, field), err_msg=field)
    assert main(['check-data', str(tmp_path / 'jittered')]) in (0, 1)  # judged, not refused


def test_an_empty_imu_topic_or_no_pose_topic_is_named(tmp_path):
    from denoise_imu_ros.data.bags import IMU_TYPE, POSE_TYPES, read_bag, TYPESTORE
    with Writer2(tmp_path / 'empty', version=9) as w:
        w.add_connection('/imu0', IMU_TYPE, typestore=TYPESTORE)
        w.add_connection('/pose', POSE_TYPES[0], typestore=TYPESTORE)
    with pytest.raises(DatasetError, match='no IMU messages on /imu0$'):
        read_bag(tmp_path / 'empty', with_pose=False)
    with pytest.raises(DatasetError, match='0 IMU and 0 pose messages, need both'):
        read_bag(tmp_path / 'empty')
    with Writer2(tmp_path / 'imu_only', version=9) as w:
        w.add_connection('/imu0', IMU_TYPE, typestore=TYPESTORE)
    with pytest.raises(DatasetError, match='no pose topic .* in this bag: this command needs '
                                           r'ground-truth poses \(topics: /imu0 '):
        read_bag(tmp_path / 'imu_only')
