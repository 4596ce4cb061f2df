# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Bags through rosbags: convert round trip, ROS 1 and ROS 2 inputs, topic errors."""

import dataclasses

from denoise_imu_ros.cli import main
from denoise_imu_ros.core.errors import DatasetError, DataWarning
from denoise_imu_ros.data.load import load_recording, load_sequence
from denoise_imu_ros.learn.config import load_config
from denoise_imu_ros.learn.train import training_split
from helpers import bag_messages, crop_asl, N, ROOT, ROS2, write_ros1_bag
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
    # named without its suffix: not found, and the bag of that name said
    with pytest.raises(DatasetError, match=r'euroc_like: no such sequence folder or bag '
                                           r'\(there is euroc_like\.bag: name it with its '
                                           r'suffix\)$'):
        load_sequence(tmp_path / 'euroc_like')


@pytest.mark.parametrize('storage, pose_type', [
    ('mcap', 'nav_msgs/msg/Odometry'), ('sqlite3', 'nav_msgs/msg/Odometry'),
    ('mcap', 'geometry_msgs/msg/PoseWithCovarianceStamped')])  # a VIO's: OpenVINS, SVO
def test_ros2_bag_with_odometry_ground_truth_and_explicit_topics(tmp_path, storage, pose_type):
    from rosbags.rosbag2 import StoragePlugin
    path = tmp_path / 'odom'
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    with Writer2(path, version=9, storage_plugin=plugin) as writer:
        conns = {}
        for topic, msgtype, stamp, msg in bag_messages(ROS2, pose_type):
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
    assert main(['convert', '--input', str(seq_dir), '--out', str(bag), '--storage', storage]) == 0
    cfg = load_config(ROOT / 'config' / 'train_euroc.yaml')
    from_csv = training_split([load_sequence(seq_dir)], cfg)
    from_bag = training_split([load_sequence(bag)], cfg)
    for name in ('imu', 'dt', 'quat', 'valid'):
        assert torch.equal(getattr(from_csv, name), getattr(from_bag, name)), name
    a, b = load_sequence(seq_dir), load_sequence(bag)
    assert np.array_equal(a.stamp_ns, b.stamp_ns) and np.array_equal(a.gt_pos, b.gt_pos)


def test_convert_refuses_an_existing_output(euroc, tmp_path, capsys):
    (tmp_path / 'out').mkdir()
    assert main(['convert', '--input', str(euroc / 'V1_02_medium'), '--out',
                 str(tmp_path / 'out')]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith('denoise-imu convert: error:') and str(tmp_path / 'out') in err
    assert '\n' not in err


def test_convert_overlap_keeps_only_the_span_with_ground_truth(euroc, tmp_path):
    from denoise_imu_ros.data.asl import read_asl
    from denoise_imu_ros.data.bags import read_bag
    # V1_02's ground truth starts ~1 s after its IMU (V1_01's corrected one does not).
    seq = euroc / 'V1_02_medium'
    assert main(['convert', '--input', str(seq), '--out', str(tmp_path / 'b'), '--overlap']) == 0
    rec, asl = read_bag(tmp_path / 'b'), read_asl(seq)
    assert asl.gt_stamp_ns[0] > asl.imu_stamp_ns[0]  # the case this test is about
    assert rec.imu_stamp_ns[0] >= asl.gt_stamp_ns[0]
    assert len(load_sequence(tmp_path / 'b')) == len(load_sequence(seq))


def test_convert_writes_the_topic_names_asked_for(tmp_path):
    from denoise_imu_ros.data.bags import read_bag
    from helpers import write_asl
    seq = write_asl(tmp_path / 'a', n_imu=600)
    assert main(['convert', '--input', str(seq), '--out', str(tmp_path / 'b'), '--imu-topic',
                 '/imu/data_raw',
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
        argv = ['convert', '--input', str(rec), '--out', str(out), '--storage', storage]
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
    # judged, not refused
    assert main(['check-data', '--input', str(tmp_path / 'jittered')]) in (0, 1)


def test_a_pose_topic_drops_and_counts_the_rows_a_trajectory_file_does(tmp_path):
    """A VIO's odometry in a bag: a pose written twice, NaN on divergence, a bad quaternion."""
    from denoise_imu_ros.data.trajectory import read_tum, write_tum
    from helpers import write_asl
    rec_dir = write_asl(tmp_path / 'asl', n_imu=1000, yaw_rate=0.3)
    bag = tmp_path / 'bag'
    assert main(['convert', '--input', str(rec_dir), '--out', str(bag)]) == 0
    good = read_bag_poses(bag)
    stamps, rows = good[0].copy(), good[1].copy()
    rows[10, 0] = np.nan                        # x
    rows[20, :4] = 0.0                          # a zero quaternion (unset)
    rows[40, :4] *= 1.02  # off unit beyond a text file's digits, not beyond a publisher's
    stamps, rows = np.insert(stamps, 31, stamps[30]), np.insert(rows, 31, rows[30], axis=0)
    spoilt = tmp_path / 'spoilt'
    _write_poses(rec_dir, spoilt, stamps, rows)
    with pytest.warns(DataWarning) as said:
        got = load_recording(spoilt)
    (warning,) = [str(w.message) for w in said]
    kept = len(stamps) - 3
    assert warning == (f'{spoilt}: /groundtruth/pose: {kept} poses kept; dropped 1 non-finite '
                       'rows, 1 rows whose quaternion is not a unit one, 1 duplicate stamps')
    # the same rows written as a trajectory file: the same poses kept, but the one a
    # float32 publisher could write (a file's digits do not excuse it)
    traj = read_tum(write_tum(tmp_path / 'asl.txt', stamps, rows[:, 4:], rows[:, :4]))
    assert traj.dropped == {'non-finite rows': 1, 'rows whose quaternion is not a unit one': 2,
                            'duplicate stamps': 1}
    got = dataclasses.replace(got, gt_stamp_ns=np.delete(got.gt_stamp_ns, 38),
                              gt_quat=np.delete(got.gt_quat, 38, axis=0),
                              gt_pos=np.delete(got.gt_pos, 38, axis=0))
    np.testing.assert_array_equal(got.gt_stamp_ns, traj.stamp_ns)
    np.testing.assert_allclose(got.gt_quat, traj.quat, atol=1e-12)
    np.testing.assert_allclose(got.gt_pos, traj.pos, atol=1e-12)


def read_bag_poses(bag):
    """Return (stamps, rows qx qy qz qw x y z) of a converted bag's pose topic."""
    from denoise_imu_ros.data.bags import read_bag
    rec = read_bag(bag)
    return rec.gt_stamp_ns, np.hstack([rec.gt_quat, rec.gt_pos])


def _write_poses(rec_dir, out, stamps, rows):
    """Write a bag of the ASL folder's IMU and these poses, as given (no check)."""
    from denoise_imu_ros.core import msgs
    from denoise_imu_ros.data.asl import read_asl
    from denoise_imu_ros.data.bags import (BAG_TYPES, imu_message, IMU_TYPE, POSE_TYPES,
                                           TYPESTORE)
    rec = read_asl(rec_dir, with_gt=False)
    t = TYPESTORE.types
    with Writer2(out, version=9) as w:
        imu = w.add_connection('/imu0', IMU_TYPE, typestore=TYPESTORE)
        pose = w.add_connection('/groundtruth/pose', POSE_TYPES[0], typestore=TYPESTORE)
        for stamp, row in zip(rec.imu_stamp_ns.tolist(), rec.imu):
            w.write(imu, stamp, TYPESTORE.serialize_cdr(imu_message(stamp, row[:3], row[3:]),
                                                        IMU_TYPE))
        for stamp, r in zip(stamps.tolist(), rows.tolist()):
            msg = t[POSE_TYPES[0]](header=msgs.header(BAG_TYPES, stamp, 'world'), pose=t[
                'geometry_msgs/msg/Pose'](position=t['geometry_msgs/msg/Point'](*r[4:]),
                                          orientation=t['geometry_msgs/msg/Quaternion'](*r[:4])))
            w.write(pose, stamp, TYPESTORE.serialize_cdr(msg, POSE_TYPES[0]))


def test_a_vios_pose_topic_said_to_be_an_estimate_gets_its_trajectory_files_recipe(
        data_dir, euroc, tmp_path):
    """VINS-Mono's poses in the bag beside the IMU, as a ROS user records a VIO's run."""
    from denoise_imu_ros.data.asl import read_asl
    from denoise_imu_ros.data.bags import write_bag
    from denoise_imu_ros.data.trajectory import read_tum, with_trajectory
    from denoise_imu_ros.learn.recipe import init_recipe
    name, vins = 'V2_01_easy', data_dir / 'euroc_vio' / 'vins_mono'
    euroc = crop_asl(euroc / name, tmp_path / 'euroc' / name, 100.0).parent  # 100 s of it
    rec = with_trajectory(read_asl(euroc / name, with_gt=False), read_tum(vins / f'{name}.txt'))
    write_bag(rec, tmp_path / 'bags' / name, pose_topic='/vins_estimator/odometry')
    from_files, _ = init_recipe(euroc, [name], poses=vins)
    from_bag, said = init_recipe(tmp_path / 'bags', [name], estimated=True)
    differ = [k for k in from_files if from_files[k] != from_bag[k]]
    assert differ == ['dataset', 'data', 'poses']
    assert from_bag['heading_weight'] == 0.0 and from_bag['rest_bias']
    assert any(line.startswith("the poses are a VIO's or SLAM's estimate") for line in said)
    # not said to be one: motion capture's recipe, and the heading's figure asks
    as_mocap, said = init_recipe(tmp_path / 'bags', [name])
    assert as_mocap['heading_weight'] == 1.0 and not as_mocap['rest_bias']
    assert any(line.startswith('heading_weight 1: the poses are taken as motion capture')
               and line.endswith('if they are an estimate, give --estimated-poses')
               for line in said)


def test_an_empty_imu_topic_or_no_pose_topic_is_named(tmp_path):
    from denoise_imu_ros.data.bags import IMU_TYPE, POSE_TYPES, read_bag, TYPESTORE
    with Writer2(tmp_path / 'empty', version=9) as w:
        w.add_connection('/imu0', IMU_TYPE, typestore=TYPESTORE)
        w.add_connection('/pose', POSE_TYPES[0], typestore=TYPESTORE)
    with pytest.raises(DatasetError, match='no IMU messages on /imu0$'):
        read_bag(tmp_path / 'empty', with_pose=False)
    with pytest.raises(DatasetError, match='0 IMU messages and 0 poses: need IMU messages '
                                           'and two poses at least'):
        read_bag(tmp_path / 'empty')
    with Writer2(tmp_path / 'imu_only', version=9) as w:
        w.add_connection('/imu0', IMU_TYPE, typestore=TYPESTORE)
    with pytest.raises(DatasetError, match='no pose topic .* in this bag: this command needs '
                                           r'ground-truth poses \(topics: /imu0 '):
        read_bag(tmp_path / 'imu_only')


def test_a_pose_with_covariance_topic_is_taken_unnamed_only_where_it_is_the_only_pose(tmp_path):
    """A pose of RViz's (/initialpose) or a localiser's beside the pose source: not a second."""
    from denoise_imu_ros.data.bags import read_bag
    pwc = 'geometry_msgs/msg/PoseWithCovarianceStamped'
    vicon = 'geometry_msgs/msg/TransformStamped'
    for name, pose, others in (('beside', vicon, [pwc]), ('only', pwc, []),
                               ('two', vicon, ['nav_msgs/msg/Odometry']),
                               ('tf', None, ['tf2_msgs/msg/TFMessage'])):
        with Writer2(tmp_path / name, version=9) as writer:
            conns = {}
            for topic, msgtype, stamp, msg in bag_messages(ROS2, pose or pwc):
                if pose is None and topic != '/imu0':
                    continue
                if topic not in conns:
                    conns[topic] = writer.add_connection(topic, msgtype, typestore=ROS2)
                writer.write(conns[topic], stamp, ROS2.serialize_cdr(msg, msgtype))
            for k, other in enumerate(others):
                writer.add_connection(f'/other{k}', other, typestore=ROS2)
    assert len(read_bag(tmp_path / 'beside').gt_stamp_ns) == N
    assert len(read_bag(tmp_path / 'only').gt_stamp_ns) == N
    with pytest.raises(DatasetError, match=r'2 candidate pose topics, pass one with '
                                           r'--pose-topic \(pose_topic in a recipe\)'):
        read_bag(tmp_path / 'two')
    with pytest.raises(DatasetError, match=r"/tf is not read: record the pose source's own "
                                           r'topic, or give its poses as trajectory files'):
        read_bag(tmp_path / 'tf')


def test_a_bag_read_again_is_read_as_it_is_now(tmp_path):
    """Reads are kept by the bag's files: a bag written anew is read anew, whatever its size."""
    from denoise_imu_ros.data.asl import read_asl
    from denoise_imu_ros.data.bags import read_bag, write_bag
    from helpers import write_asl
    first = read_asl(write_asl(tmp_path / 'a', n_imu=600, yaw_rate=0.2))
    write_bag(first, tmp_path / 'bag')
    read = read_bag(tmp_path / 'bag')
    read.imu[:] = 0.0  # what a caller does to its copy stays there
    again = read_bag(tmp_path / 'bag')
    np.testing.assert_array_equal(again.imu, first.imu)
    np.testing.assert_array_equal(again.gt_quat, first.gt_quat)
    second = read_asl(write_asl(tmp_path / 'b', n_imu=600, yaw_rate=0.5))  # the same size
    for f in (tmp_path / 'bag').iterdir():
        f.unlink()
    (tmp_path / 'bag').rmdir()
    write_bag(second, tmp_path / 'bag')
    np.testing.assert_array_equal(read_bag(tmp_path / 'bag').imu, second.imu)


def test_a_bag_read_again_says_again_what_it_drops_and_what_it_lacks(tmp_path):
    from denoise_imu_ros.data.bags import IMU_TYPE, read_bag, TYPESTORE
    from helpers import write_asl
    rec_dir = write_asl(tmp_path / 'asl', n_imu=400, yaw_rate=0.3)
    assert main(['convert', '--input', str(rec_dir), '--out', str(tmp_path / 'bag')]) == 0
    stamps, rows = read_bag_poses(tmp_path / 'bag')
    _write_poses(rec_dir, tmp_path / 'twice', np.insert(stamps, 31, stamps[30]),
                 np.insert(rows, 31, rows[30], axis=0))
    for _ in range(2):
        with pytest.warns(DataWarning, match='dropped 1 duplicate stamps'):
            read_bag(tmp_path / 'twice')
    with Writer2(tmp_path / 'empty', version=9) as w:
        w.add_connection('/imu0', IMU_TYPE, typestore=TYPESTORE)
    for _ in range(2):
        with pytest.raises(DatasetError, match='no IMU messages on /imu0$'):
            read_bag(tmp_path / 'empty', with_pose=False)
