# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""process-bag: what the node publishes, written into a copy of a bag."""

from denoise_imu_ros.cli import main
from denoise_imu_ros.core.errors import DatasetError
from helpers import crop_bag, N, SAMPLE, sample_messages, write_ros1_bag
import numpy as np
import pytest


def _fields(m) -> list[float]:
    """Every number of a sensor_msgs/Imu (rclpy or rosbags)."""
    o, w, a = m.orientation, m.angular_velocity, m.linear_acceleration
    return [w.x, w.y, w.z, *m.angular_velocity_covariance, a.x, a.y, a.z,
            *m.linear_acceleration_covariance, o.x, o.y, o.z, o.w, *m.orientation_covariance]


@pytest.mark.parametrize('rest,track,guard,heading', [
    (False, False, 'model', 1.0), (True, False, 'model', 1.0), (True, True, 'model', 1.0),
    (True, True, 'off', 0.0)])
def test_process_bag_writes_exactly_what_the_node_publishes(harness, model_file, tmp_path,
                                                            rest, track, guard, heading):
    """
    With the model's filter settings, a turn-on bias removed, the output's bias tracked.

    And the last two with an input envelope the bag's motion leaves: guarded (the fallback
    beyond it), and with the guard turned off, that model taught without its poses' heading
    (its correction about the vertical dropped); both with variances for each message.
    """
    from denoise_imu_ros.cli import main as cli
    from denoise_imu_ros.core.modelfile import add_metadata
    from denoise_imu_ros.pipeline.rest_bias import RestBiasSettings
    from denoise_imu_ros.pipeline.fusion import FusionSettings
    from rosbags.highlevel import AnyReader
    # settings stored as tune-fusion stores them: both paths must apply all of them
    add_metadata(model_file, fusion={'settings': FusionSettings(
        4.0, False, (0.02, -0.1, 0.05)).as_dict(), 'orientation_std_rad': [0.01, 0.02, 0.03]},
        rest_bias=RestBiasSettings(prior_rad_s=(0.01, -0.02, 0.03)).to_dict() if rest else None,
        bias_tracking={'sigma_motion_deg_s': 0.05, 'forgetting_s': 30.0} if track else None,
        input_envelope={'gyro_rad_s': 0.002, 'accel_offset_m_s2': 3.0,
                        'sustained_accel_m_s2': 0.025} if track else None,
        blend={'weight': 0.6, 'tracking': {'sigma_motion_deg_s': 0.1, 'forgetting_s': 100.0}}
        if track else None,
        gyro_variance={'theta': [-7.5, 1.5, 2.0, -1.5]} if track else None,
        accel_variance={'theta': [-4.4, 0.6, 1.1, 0.1], 'accel_bias_m_s2': [0.02, -0.1, 0.05]}
        if track else None,
        train_config={'heading_weight': heading})
    bag = crop_bag(SAMPLE, tmp_path / 'head', 3.5)  # every topic, 700 IMU messages
    assert cli(['process-bag', '--input', str(bag), '--out', str(tmp_path / 'out'), '--model',
                str(model_file), '--envelope-guard', guard]) == 0
    with AnyReader([bag]) as reader:
        given = {c.topic: c.msgcount for c in reader.connections}
    with AnyReader([tmp_path / 'out']) as reader:
        topics = {c.topic: c.msgcount for c in reader.connections}
        bags = {}
        for topic in ('/imu/corrected', '/imu/data'):
            conns = [c for c in reader.connections if c.topic == topic]
            bags[topic] = []
            for conn, _, raw in reader.messages(connections=conns):
                bags[topic].append(_fields(reader.deserialize(raw, conn.msgtype)))
    assert (topics['/imu0'] == topics['/imu/corrected'] == topics['/imu/data']
            == topics['/imu/attitude'] == given['/imu0'] > 600)
    assert topics['/groundtruth/pose'] == given['/groundtruth/pose'] > 0  # copied through
    from denoise_imu_ros.runtime.player import read_imu_messages
    h = harness(envelope_guard=guard)
    h.send(read_imu_messages(bag))  # the bag's own messages, every field
    assert np.array_equal(np.array([_fields(m) for m in h.corrected]),
                          np.array(bags['/imu/corrected']))
    # the gravity-aided orientation, bit for bit, with its covariance
    assert np.array_equal(np.array([_fields(m) for m in h.fused]), np.array(bags['/imu/data']))
    assert bags['/imu/data'][0][-9] > 0  # orientation provided (REP-145)
    for column in (3, 15):  # angular_velocity_ and linear_acceleration_covariance[0]
        variances = {row[column] for row in bags['/imu/corrected']}
        assert len(variances) > (600 if track else 0) and (len(variances) == 1) != track
    h.diagnostics.clear()
    h.spin_until(lambda: h.diagnostics, timeout=5.0)
    diagnostics = {v.key: v.value for v in h.diagnostics[-1].status[0].values}
    assert diagnostics['rest_bias_applied'] == str(rest)
    assert diagnostics['tracked_bias_applied'] == str(track)
    assert diagnostics['vertical_correction_dropped'] == str(heading == 0)
    assert diagnostics['envelope_guard_applied'] == str(track and guard == 'model')
    assert diagnostics['classical_blend_applied'] == str(track)
    if track and guard == 'model':  # over a second 0.025 m/s^2 off gravity: the classical alone
        assert int(diagnostics['classical_only_samples']) > 0
    if track and guard == 'model':  # the still start's noise exceeds 0.002 rad/s
        assert int(diagnostics['envelope_guarded_samples']) > 0
    assert ('tracked_bias_rad_s' in diagnostics) == track
    if track:  # faster than 0.002 rad/s throughout: the tracker holds its estimate
        assert diagnostics['tracked_bias_held'] == str(guard == 'model')
    if rest:  # the bundled sample starts moving: the model's prior, said so
        assert diagnostics['rest_bias_source'] == 'prior'
        assert diagnostics['rest_bias_rad_s'] == '0.010000 -0.020000 0.030000'


def test_process_bag_withholds_what_the_node_withholds_on_a_jittered_stretch(
        harness, model_file, tmp_path):
    """Stamps 4.6 / 5.4 ms apart for a while: the median rate passes, the samples are suspect."""
    from denoise_imu_ros.data.bags import imu_message, IMU_TYPE, TYPESTORE
    from denoise_imu_ros.data.load import load_imu
    from helpers import imu_msg
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag2 import Writer
    rec = load_imu(SAMPLE)
    steps = np.full(800, 5_000_000)
    steps[400:460] += np.where(np.arange(60) % 2, 400_000, -400_000)
    stamps = rec.imu_stamp_ns[0] + np.concatenate([[0], np.cumsum(steps[1:])])
    with Writer(tmp_path / 'jittered', version=9) as w:
        conn = w.add_connection('/imu0', IMU_TYPE, typestore=TYPESTORE)
        for t, row in zip(stamps, rec.imu):
            w.write(conn, int(t), TYPESTORE.serialize_cdr(
                imu_message(int(t), row[:3], row[3:]), IMU_TYPE))
    assert main(['process-bag', '--input', str(tmp_path / 'jittered'), '--out',
                 str(tmp_path / 'out'),
                 '--model', str(model_file)]) == 0
    with AnyReader([tmp_path / 'out']) as reader:
        written = {c.topic: sorted(t for _, t, _ in reader.messages(connections=[c]))
                   for c in reader.connections}
    h = harness()
    h.send([imu_msg(t, r[:3], r[3:]) for t, r in zip(stamps, rec.imu)])
    assert h.node.corrected_withheld > 40  # the stretch is suspect
    published = [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for m in h.corrected]
    assert written['/imu/corrected'] == published
    assert len(written['/imu/data']) == len(h.fused)


def test_process_bag_converts_a_ros1_bag_and_adds_the_outputs(tmp_path, model_file):
    from rosbags.highlevel import AnyReader
    path = write_ros1_bag(tmp_path / 'in.bag')
    assert main(['process-bag', '--input', str(path), '--out', str(tmp_path / 'out'), '--model',
                 str(model_file), '--storage', 'sqlite3']) == 0
    with AnyReader([tmp_path / 'out']) as reader:
        topics = {c.topic: c.msgcount for c in reader.connections}
    assert topics == {'/imu0': N, '/vicon/body': N, '/imu/corrected': N, '/imu/data': N,
                      '/imu/attitude': N}


def test_a_failed_process_bag_leaves_nothing_behind_and_the_retry_works(
        model_file, tmp_path, monkeypatch):
    from denoise_imu_ros.data.bags import read_bag
    from denoise_imu_ros.pipeline.online import OnlineDenoiser
    from helpers import write_asl
    assert main(['convert', '--input', str(write_asl(tmp_path / 'a', n_imu=1200)),
                 '--out', str(tmp_path / 'in')]) == 0
    real = OnlineDenoiser.process_imu
    calls = []

    def fail_half_way(self, msg):
        calls.append(1)
        if len(calls) == 600:
            raise DatasetError('disk full (simulated)')
        return real(self, msg)
    monkeypatch.setattr(OnlineDenoiser, 'process_imu', fail_half_way)
    assert main(['process-bag', '--input', str(tmp_path / 'in'), '--out', str(tmp_path / 'out'),
                 '--model', str(model_file)]) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ['a', 'in', 'model.safetensors']
    monkeypatch.setattr(OnlineDenoiser, 'process_imu', real)
    assert main(['process-bag', '--input', str(tmp_path / 'in'), '--out', str(tmp_path / 'out'),
                 '--model', str(model_file)]) == 0
    assert len(read_bag(tmp_path / 'out', imu_topic='/imu/corrected').imu) == 1200


def test_every_offline_tool_refuses_a_stream_at_another_rate(model_file, tmp_path, capsys):
    from helpers import write_asl
    slow = write_asl(tmp_path / 'slow', n_imu=2000, imu_rate=100.0)
    assert main(['convert', '--input', str(slow), '--out', str(tmp_path / 'slow_bag')]) == 0
    capsys.readouterr()
    for cmd in (['process-bag', '--input', str(tmp_path / 'slow_bag'), '--out',
                 str(tmp_path / 'out')],
                ['correct', '--input', str(tmp_path / 'slow_bag'), '--out',
                 str(tmp_path / 'o.csv')],
                ['eval', '--data', str(tmp_path), '--sequences', 'slow_bag', '--out',
                 str(tmp_path / 'e'), '--no-plots'],
                ['noise', '--data', str(tmp_path), '--sequences', 'slow_bag', '--out',
                 str(tmp_path / 'n')]):
        assert main(cmd + ['--model', str(model_file)]) == 1
        assert 'IMU rate 100.0 Hz, the model was trained at 200.0 Hz' in capsys.readouterr().err
    assert not (tmp_path / 'out').exists() and not (tmp_path / 'o.csv').exists()


def test_a_non_finite_input_covariance_is_never_published(harness, tmp_path):
    """A NaN accelerometer covariance in, zeros ('unknown') out, counted."""
    import math
    from denoise_imu_ros.cli import main as cli
    from denoise_imu_ros.core import msgs
    from denoise_imu_ros.data.bags import BAG_TYPES, IMU_TYPE, TYPESTORE
    from helpers import imu_msg, write_untrained_model
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag2 import Writer
    model = write_untrained_model(tmp_path / 'm.safetensors', {'sample_rate_hz': 200.0})
    stamps = 10**9 + 5_000_000 * np.arange(600)
    nan_cov = [math.nan] + [0.0] * 8
    h = harness()
    sent = [imu_msg(t, [0, 0, 0.1], [0, 0, 9.81]) for t in stamps]
    for m in sent:
        m.linear_acceleration_covariance[0] = math.nan
    h.send(sent)
    assert h.node._denoiser.counts['non_finite_covariance'] == 600
    for m in h.corrected + h.fused:
        assert list(m.linear_acceleration_covariance) == [0.0] * 9
    with Writer(tmp_path / 'in', version=9) as w:
        conn = w.add_connection('/imu', IMU_TYPE, typestore=TYPESTORE)
        for t in stamps:
            msg = msgs.imu(BAG_TYPES, msgs.header(BAG_TYPES, int(t), 'imu'), [0, 0, 0.1],
                           [0, 0, 9.81], accel_cov=nan_cov)
            w.write(conn, int(t), TYPESTORE.serialize_cdr(msg, IMU_TYPE))
    assert cli(['process-bag', '--input', str(tmp_path / 'in'), '--out', str(tmp_path / 'out'),
                '--model', str(model)]) == 0
    with AnyReader([tmp_path / 'out']) as reader:
        conns = [c for c in reader.connections if c.topic in ('/imu/corrected', '/imu/data')]
        covs = [reader.deserialize(raw, c.msgtype).linear_acceleration_covariance
                for c, _, raw in reader.messages(connections=conns)]
    assert len(covs) == 1200 and all(np.array_equal(c, np.zeros(9)) for c in covs)


def test_receive_order_jitter_drops_nothing_and_qos_and_compression_are_kept(
        tmp_path, model_file):
    """Receive times out of stamp order: nothing dropped; recorded QoS and zstd kept."""
    from denoise_imu_ros.cli import main as cli
    from denoise_imu_ros.core import msgs
    from denoise_imu_ros.data.bags import BAG_TYPES, IMU_TYPE, TYPESTORE
    from rosbags.highlevel import AnyReader
    from rosbags.interfaces import (Qos, QosDurability, QosHistory, QosLiveliness,
                                    QosReliability, QosTime)
    from rosbags.rosbag2 import Writer
    from helpers import crop_bag
    head = crop_bag(SAMPLE, tmp_path / 'head', 16.0)  # the sample's first 3000 and more
    imu = sample_messages(3000)
    rng = np.random.default_rng(0)
    latency = rng.uniform(1e6, 15e6, len(imu)).astype(np.int64)  # 1-15 ms of transport
    never = QosTime(sec=0, nsec=0)
    static = Qos(history=QosHistory.KEEP_LAST, depth=1, reliability=QosReliability.RELIABLE,
                 durability=QosDurability.TRANSIENT_LOCAL, deadline=never, lifespan=never,
                 liveliness=QosLiveliness.AUTOMATIC, liveliness_lease_duration=never,
                 avoid_ros_namespace_conventions=False)
    with Writer(tmp_path / 'jittered', version=9) as w:
        conn = w.add_connection('/imu0', IMU_TYPE, typestore=TYPESTORE)
        tf = w.add_connection('/tf_static', 'tf2_msgs/msg/TFMessage', typestore=TYPESTORE,
                              offered_qos_profiles=[static])
        w.write(tf, 1, TYPESTORE.serialize_cdr(TYPESTORE.types['tf2_msgs/msg/TFMessage'](
            transforms=[]), 'tf2_msgs/msg/TFMessage'))
        for k in np.argsort([msgs.stamp_ns(m.header) + d for m, d in zip(imu, latency)]):
            m = msgs.copy_imu(BAG_TYPES, imu[k])
            w.write(conn, msgs.stamp_ns(m.header) + int(latency[k]),
                    TYPESTORE.serialize_cdr(m, IMU_TYPE))
    assert cli(['process-bag', '--input', str(tmp_path / 'jittered'), '--out',
                str(tmp_path / 'out'),
                '--model', str(model_file), '--compress']) == 0
    assert cli(['process-bag', '--input', str(head), '--out', str(tmp_path / 'ordered'),
                '--model', str(model_file)]) == 0

    def corrected(bag):
        with AnyReader([bag]) as reader:
            conns = [c for c in reader.connections if c.topic == '/imu/corrected']
            got = {}
            for c, _, raw in reader.messages(connections=conns):
                m = reader.deserialize(raw, c.msgtype)
                got[msgs.stamp_ns(m.header)] = (m.angular_velocity.x, m.angular_velocity.z)
            qos = {c.topic: c.ext.offered_qos_profiles for c in reader.connections}
            return got, qos
    jittered, qos = corrected(tmp_path / 'out')
    ordered, _ = corrected(tmp_path / 'ordered')
    assert len(jittered) == 3000  # nothing dropped as out of order
    with AnyReader([tmp_path / 'out']) as reader:  # each output once, at its input's time
        times = {}
        for c, t, raw in reader.messages():
            if c.topic != '/tf_static':
                m = reader.deserialize(raw, c.msgtype)
                times.setdefault(c.topic, []).append((msgs.stamp_ns(m.header), t))
    for topic in ('/imu/corrected', '/imu/data', '/imu/attitude'):
        assert sorted(times[topic]) == sorted(times['/imu0']), topic
    assert all(jittered[t] == ordered[t] for t in jittered)  # what header order gives
    # transient local kept, for the late subscribers of a replay
    assert qos['/tf_static'][0].durability == QosDurability.TRANSIENT_LOCAL
    size = sum(f.stat().st_size for f in (tmp_path / 'out').iterdir())
    plain = tmp_path / 'plain'
    assert cli(['process-bag', '--input', str(tmp_path / 'jittered'), '--out', str(plain),
                '--model',
                str(model_file)]) == 0
    assert size < 0.7 * sum(f.stat().st_size for f in plain.iterdir())
    # an input compressed inside its MCAP chunks (metadata.yaml says nothing) stays so
    from denoise_imu_ros.data.bags import is_compressed, open_bag
    from helpers import write_asl
    assert cli(['convert', '--input', str(write_asl(tmp_path / 'asl', n_imu=1200)), '--out',
                str(tmp_path / 'zstd'),
                '--compress']) == 0
    assert cli(['process-bag', '--input', str(tmp_path / 'zstd'), '--out', str(tmp_path / 'kept'),
                '--model', str(model_file)]) == 0
    with open_bag(tmp_path / 'kept') as reader:
        assert is_compressed(reader)


def test_a_bag_that_has_an_output_topic_already_is_refused_or_namespaced(
        tmp_path, model_file, capsys):
    """Many drivers publish the raw IMU on /imu/data: the output must not mix with it."""
    from denoise_imu_ros.runtime.process_bag import output_topics
    from rosbags.highlevel import AnyReader
    from helpers import write_asl
    assert main(['convert', '--input', str(write_asl(tmp_path / 'a', n_imu=1200)), '--out',
                 str(tmp_path / 'in'),
                 '--imu-topic', '/imu/data']) == 0
    capsys.readouterr()
    assert main(['process-bag', '--input', str(tmp_path / 'in'), '--out', str(tmp_path / 'out'),
                 '--model', str(model_file)]) == 1
    assert 'it has /imu/data already' in capsys.readouterr().err
    assert not (tmp_path / 'out').exists()
    assert main(['process-bag', '--input', str(tmp_path / 'in'), '--out', str(tmp_path / 'out'),
                 '--model',
                 str(model_file), '--namespace', '/denoised']) == 0
    with AnyReader([tmp_path / 'out']) as reader:
        topics = {c.topic: c.msgcount for c in reader.connections}
    assert topics == {'/imu/data': 1200, '/groundtruth/pose': 1200,
                      '/denoised/imu/corrected': 1200, '/denoised/imu/data': 1200,
                      '/denoised/imu/attitude': 1200}
    assert main(['process-bag', '--input', str(tmp_path / 'out'), '--out',
                 str(tmp_path / 'again'), '--model',
                 str(model_file), '--namespace', '/denoised']) == 1  # its own outputs now
    err = capsys.readouterr().err
    assert 'it has /denoised/imu/attitude' in err and 'e.g. --namespace /denoised2 (' in err
    assert output_topics('robot/') == ('/robot/imu/corrected', '/robot/imu/data',
                                       '/robot/imu/attitude')
    assert main(['process-bag', '--input', str(tmp_path / 'in'), '--out', str(tmp_path / 'o2'),
                 '--model',
                 str(model_file), '--namespace', '/9bad']) == 1
    assert 'not a ROS namespace' in capsys.readouterr().err


def test_a_ros2_bag_folder_named_like_a_ros1_bag_is_read_as_ros2(tmp_path, model_file):
    from helpers import write_asl
    assert main(['convert', '--input', str(write_asl(tmp_path / 'a', n_imu=1200)),
                 '--out', str(tmp_path / 'in.bag')]) == 0
    assert main(['process-bag', '--input', str(tmp_path / 'in.bag'), '--out',
                 str(tmp_path / 'out'),
                 '--model', str(model_file)]) == 0
    from denoise_imu_ros.data.bags import read_bag
    assert len(read_bag(tmp_path / 'in.bag').imu) == len(read_bag(
        tmp_path / 'out', imu_topic='/imu/corrected').imu) == 1200


def test_a_clock_set_back_mid_bag_is_two_sessions_not_one_interleaved(tmp_path, model_file):
    """Sorting by stamp across a clock reset would interleave two recordings' samples."""
    from denoise_imu_ros.core import msgs
    from denoise_imu_ros.data.bags import BAG_TYPES, IMU_TYPE, TYPESTORE
    from denoise_imu_ros.runtime.process_bag import process_bag, stamp_order
    from denoise_imu_ros.runtime.settings import Settings
    from rosbags.rosbag2 import Writer
    imu = sample_messages(1200)
    t0 = msgs.stamp_ns(imu[0].header)
    stamps = [t0 + 5_000_000 * k for k in range(600)]  # 3 s, then the clock goes back
    stamps += [t0 + 2_500_000 + 5_000_000 * k for k in range(600)]  # inside the first
    with Writer(tmp_path / 'in', version=9) as w:
        conn = w.add_connection('/imu0', IMU_TYPE, typestore=TYPESTORE)
        for k, (m, t) in enumerate(zip(imu, stamps)):
            m = msgs.copy_imu(BAG_TYPES, m)
            m.header = msgs.header(BAG_TYPES, t, 'imu0')
            w.write(conn, t0 + 5_000_000 * k, TYPESTORE.serialize_cdr(m, IMU_TYPE))
    counts = process_bag(tmp_path / 'in', tmp_path / 'out', Settings(model=str(model_file)))
    assert counts['accepted'] == 1200 and counts['time_jump_resets'] == 1
    assert counts.get('gap_resets', 0) == 0 and counts['out_of_order'] == 0
    order = stamp_order(np.array([5, 3, 4, 100, 90, 2, 1]), 50)
    assert order.tolist() == [1, 2, 0, 4, 3, 6, 5]  # the 2 starts a session


def test_a_node_restarted_mid_bag_starts_afresh_as_process_bag_on_the_rest(
        harness, model_file, tmp_path):
    """
    A node stopped and started again while the IMU streams: nothing of the first run is kept.

    The first found the turn-on bias in a still start; the second, started in motion, is a
    fresh start on what it receives: what `process-bag` writes for the rest of the bag, bit
    for bit, with the model's prior turn-on bias, said so in /diagnostics.
    """
    from denoise_imu_ros.core import msgs
    from denoise_imu_ros.core.modelfile import add_metadata
    from denoise_imu_ros.data.bags import BAG_TYPES, IMU_TYPE, TYPESTORE
    from denoise_imu_ros.pipeline.rest_bias import RestBiasSettings
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag2 import Writer
    add_metadata(model_file, rest_bias=RestBiasSettings(prior_rad_s=(0.01, -0.02, 0.03)).to_dict(),
                 bias_tracking={'sigma_motion_deg_s': 0.05, 'forgetting_s': 30.0})
    from helpers import imu_msg
    imu = sample_messages(1400)
    t0 = msgs.stamp_ns(imu[0].header)
    still = [imu_msg(t0 - 5_000_000 * (400 - k), (0.02, -0.01, 0.04), (0.0, 0.0, 9.81))
             for k in range(400)]  # 2 s still at a bias other than the prior
    first = harness()
    first.send(still + imu[:700])
    assert len(first.corrected) == 1100
    first.diagnostics.clear()
    first.spin_until(lambda: first.diagnostics, timeout=5.0)
    said = {v.key: v.value for v in first.diagnostics[-1].status[0].values}
    assert said['rest_bias_source'] == 'stillness'
    first.close()
    with Writer(tmp_path / 'rest', version=9) as w:
        conn = w.add_connection('/imu0', IMU_TYPE, typestore=TYPESTORE)
        for m in imu[700:]:
            w.write(conn, msgs.stamp_ns(m.header), TYPESTORE.serialize_cdr(
                msgs.copy_imu(BAG_TYPES, m), IMU_TYPE))
    assert main(['process-bag', '--input', str(tmp_path / 'rest'), '--out', str(tmp_path / 'out'),
                 '--model', str(model_file)]) == 0
    with AnyReader([tmp_path / 'out']) as reader:
        conns = [c for c in reader.connections if c.topic == '/imu/corrected']
        written = [_fields(reader.deserialize(raw, c.msgtype))
                   for c, _, raw in reader.messages(connections=conns)]
    second = harness()
    second.send(imu[700:])
    assert len(written) == len(second.corrected) == 700
    assert np.array_equal(np.array([_fields(m) for m in second.corrected]), np.array(written))
    second.diagnostics.clear()
    second.spin_until(lambda: second.diagnostics, timeout=5.0)
    said = {v.key: v.value for v in second.diagnostics[-1].status[0].values}
    assert said['rest_bias_source'] == 'prior' and said['accepted'] == '700'


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_a_host_clock_stepped_back_is_read_as_the_node_received_it(harness, tmp_path,
                                                                   model_file, storage):
    """NTP steps stamps and receive times alike: process-bag writes what the node publishes."""
    from denoise_imu_ros.core import msgs
    from denoise_imu_ros.core.modelfile import read_model_file
    from denoise_imu_ros.data.bags import (BAG_TYPES, IMU_TYPE, messages_as_written,
                                           open_bag, TYPESTORE)
    from denoise_imu_ros.pipeline.online import OnlineDenoiser
    from denoise_imu_ros.runtime.process_bag import process_bag
    from denoise_imu_ros.runtime.settings import Settings
    from rosbags.rosbag2 import StoragePlugin, Writer
    imu = sample_messages(1200)
    t0 = msgs.stamp_ns(imu[0].header)
    stamps = [t0 + 5_000_000 * k for k in range(600)]  # 3 s, then the clock goes back 2 s
    stamps += [t0 + 1_000_000_000 + 5_000_000 * k for k in range(600)]
    sent = []
    with Writer(tmp_path / 'in', version=9, storage_plugin=StoragePlugin[storage.upper()]) as w:
        conn = w.add_connection('/imu0', IMU_TYPE, typestore=TYPESTORE)
        for m, t in zip(imu, stamps):
            m = msgs.copy_imu(BAG_TYPES, m)
            m.header = msgs.header(BAG_TYPES, t, 'imu0')
            w.write(conn, t + 2_000_000, TYPESTORE.serialize_cdr(m, IMU_TYPE))
            sent.append(m)
    warned = []
    counts = process_bag(tmp_path / 'in', tmp_path / 'out', Settings(model=str(model_file)),
                         storage=storage, warn=warned.append)
    assert counts['accepted'] == 1200 and counts['time_jump_resets'] == 1
    assert counts['duplicate_stamp'] == counts['out_of_order'] == 0
    assert warned == [f'{tmp_path / "in"}: its IMU stamps step back 1 time as written (a '
                      'clock set back, a driver restarted): each starts a new run, as the '
                      'node that received them did']
    loaded = read_model_file(model_file)
    node = OnlineDenoiser.from_model_file(loaded, loaded.meta.fusion.chosen)
    expected = [node.process_imu(m).gyro for m in sent]  # as the node received them
    with open_bag(tmp_path / 'out') as rd:
        written = [rd.deserialize(raw, c.msgtype).angular_velocity
                   for c, _, raw in messages_as_written(rd) if c.topic == '/imu/corrected']
    assert np.array_equal(np.array([[v.x, v.y, v.z] for v in written]), np.array(expected))
    if storage == 'mcap':  # and the node itself, sent the stream as it was recorded
        live = harness()
        live.send([msgs.copy_imu(msgs.rclpy_types(), m) for m in sent])
        assert live.node._denoiser.counts['time_jump_resets'] == 1
        assert np.array_equal(np.array([[m.angular_velocity.x, m.angular_velocity.y,
                                         m.angular_velocity.z] for m in live.corrected]),
                              np.array(expected))


def test_imu_stamps_on_two_clocks_are_refused_in_one_line_and_nothing_is_written(
        tmp_path, model_file, capsys):
    """Every 10th message 12 years later: not 800 one-sample recordings, exit 0."""
    from denoise_imu_ros.core import msgs
    from denoise_imu_ros.data.bags import BAG_TYPES, IMU_TYPE, TYPESTORE
    from rosbags.rosbag2 import Writer
    imu = sample_messages(1000)
    t0 = msgs.stamp_ns(imu[0].header)
    with Writer(tmp_path / 'in', version=9) as w:
        conn = w.add_connection('/imu0', IMU_TYPE, typestore=TYPESTORE)
        for k, m in enumerate(imu):
            m = msgs.copy_imu(BAG_TYPES, m)
            t = t0 + 5_000_000 * k + (12 * 365 * 86400 * 10**9 if k % 10 == 9 else 0)
            m.header = msgs.header(BAG_TYPES, t, 'imu0')
            w.write(conn, t0 + 5_000_000 * k, TYPESTORE.serialize_cdr(m, IMU_TYPE))
    assert main(['process-bag', '--input', str(tmp_path / 'in'), '--out', str(tmp_path / 'out'),
                 '--model',
                 str(model_file)]) == 1
    err = capsys.readouterr().err.strip()
    assert 'its IMU stamps jump between clocks' in err and 'two clocks on one topic?' in err
    assert len(err.splitlines()) == 1 and not (tmp_path / 'out').exists()


def test_sigterm_during_process_bag_leaves_no_partial_bag(tmp_path):
    import signal
    import subprocess
    import sys
    import time
    proc = subprocess.Popen([sys.executable, '-m', 'denoise_imu_ros.cli', 'process-bag',
                             '--input', str(SAMPLE), '--out', str(tmp_path / 'out'),
                             '--model', 'euroc'],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not list(tmp_path.glob('.out.*')) and time.monotonic() < deadline:
        time.sleep(0.01)  # the hidden partial bag exists: it is being written
    assert list(tmp_path.glob('.out.*')), 'process-bag never started writing'
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143 and err.strip() == 'denoise-imu process-bag: terminated'
    assert list(tmp_path.iterdir()) == []  # neither the bag nor its hidden partial copy


@pytest.mark.parametrize('fused', [True, False])
def test_process_bag_with_the_nodes_params_file_writes_what_that_node_publishes(
        harness, model_file, tmp_path, fused):
    """
    Every parameter that changes a number, off its default, from one file for both.

    The stream has a 4-period gap (a gap at the default max_gap_factor, not at 5) and
    then steps back 0.8 s (a new run at a 0.5 s threshold; at the default 1 s, late
    samples that process-bag would put in stamp order).
    """
    from denoise_imu_ros.core import msgs
    from denoise_imu_ros.core.modelfile import add_metadata
    from denoise_imu_ros.data.bags import BAG_TYPES, IMU_TYPE, TYPESTORE
    from denoise_imu_ros.pipeline.rest_bias import RestBiasSettings
    from denoise_imu_ros.runtime.player import read_imu_messages
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag2 import Writer
    import yaml
    add_metadata(model_file,
                 rest_bias=RestBiasSettings(prior_rad_s=(0.01, -0.02, 0.03)).to_dict(),
                 bias_tracking={'sigma_motion_deg_s': 0.05, 'forgetting_s': 30.0},
                 input_envelope={'gyro_rad_s': 0.002, 'accel_offset_m_s2': 3.0},
                 blend={'weight': 0.5, 'tracking': {'sigma_motion_deg_s': 0.1,
                                                    'forgetting_s': 100.0}})
    imu = sample_messages(700)
    t0 = msgs.stamp_ns(imu[0].header)
    stamps = [t0 + 5_000_000 * (k if k < 300 else k + 3) for k in range(600)]
    stamps += [stamps[-1] - 800_000_000 + 5_000_000 * k for k in range(100)]
    with Writer(tmp_path / 'in', version=9) as w:
        conn = w.add_connection('/imu0', IMU_TYPE, typestore=TYPESTORE)
        for k, (m, t) in enumerate(zip(imu, stamps)):
            m = msgs.copy_imu(BAG_TYPES, m)
            m.header = msgs.header(BAG_TYPES, t, 'imu0')
            w.write(conn, t0 + 5_000_000 * k, TYPESTORE.serialize_cdr(m, IMU_TYPE))
    params = {'fixed_frame': 'map', 'embed_attitude': True, 'orientation_stddev': 0.2,
              'angular_velocity_stddev': 0.003, 'linear_acceleration_stddev': 0.02,
              'max_gap_factor': 5.0,
              'time_jump_threshold': 0.5, 'rate_tolerance': 0.1, 'publish_fused': fused,
              'fusion_tau_acc': 7.0, 'fusion_bias_estimation': 'on',
              'fusion_classical_tilt': 'on', 'fusion_accel_bias': 'off', 'rest_bias': 'off',
              'envelope_guard': 'off',
              'classical_blend': 'off', 'fused_orientation_stddev': 0.02}
    from denoise_imu_ros.runtime.settings import Settings  # every one but the model's and depth
    assert set(params) == {n for n, _, _ in Settings.specs()} - {'model', 'input_queue_depth'}
    path = tmp_path / 'params.yaml'
    path.write_text(yaml.safe_dump({'/**': {'ros__parameters': {
        'model': str(model_file), **params}}}))
    assert main(['process-bag', '--input', str(tmp_path / 'in'), '--out', str(tmp_path / 'out'),
                 '--params-file',
                 str(path)]) == 0
    written = {}
    with AnyReader([tmp_path / 'out']) as reader:
        for topic in ('/imu/corrected', '/imu/data', '/imu/attitude'):
            conns = [c for c in reader.connections if c.topic == topic]
            written[topic] = [reader.deserialize(raw, c.msgtype) for c, _, raw in
                              reader.messages(connections=conns)] if conns else []
    assert bool(written['/imu/data']) == fused
    assert len(written['/imu/corrected']) == 700
    h = harness(**params)
    h.send(read_imu_messages(tmp_path / 'in'))
    counts = h.node._denoiser.counts
    assert counts['accepted'] == 700 and counts['time_jump_resets'] == 1
    assert counts['gap_resets'] == 0 and counts['skipped_periods'] == 3
    assert np.array_equal(np.array([_fields(m) for m in h.corrected]),
                          np.array([_fields(m) for m in written['/imu/corrected']]))
    assert np.array_equal(np.array([_fields(m) for m in h.fused]),
                          np.array([_fields(m) for m in written['/imu/data']]))
    assert [(m.header.frame_id, m.quaternion.x, m.quaternion.w) for m in h.attitude] == [
        (m.header.frame_id, m.quaternion.x, m.quaternion.w) for m in written['/imu/attitude']]
    assert written['/imu/corrected'][0].orientation_covariance[0] == pytest.approx(0.04)
    assert written['/imu/corrected'][0].linear_acceleration_covariance[0] == pytest.approx(4e-4)
