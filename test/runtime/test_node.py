# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The gyro_denoiser node in-process: topics, headers, bad input, fuzz, services."""

import os
import re

from denoise_imu_ros.data.load import load_imu
from denoise_imu_ros.learn.checkpoint import load_model, save_model
from denoise_imu_ros.learn.model import correct_gyro
from denoise_imu_ros.pipeline.online import DROP_CAUSES
from denoise_imu_ros.runtime.node import main, PARAMETERS
from diagnostic_msgs.msg import DiagnosticStatus
from helpers import DOMAIN, imu_msg, ROOT, SAMPLE, untrained_model
import numpy as np
import pytest
from rclpy.qos import ReliabilityPolicy
from std_srvs.srv import Trigger

NODE_PARAMETERS = {name: default for name, default, _ in PARAMETERS}


def test_corrected_imu_copies_headers_and_matches_the_batch_network(harness, model_file):
    rec = load_imu(SAMPLE)
    n = 700
    h = harness(fixed_frame='world')
    h.send([imu_msg(t, r[:3], r[3:]) for t, r in zip(rec.imu_stamp_ns[:n], rec.imu[:n])])
    got = np.array([[m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z]
                    for m in h.corrected])
    np.testing.assert_allclose(got, correct_gyro(load_model(model_file).model, rec.imu[:n]),
                               atol=1e-6)
    first = h.corrected[0]
    assert first.header.frame_id == 'imu4'
    assert first.header.stamp.sec * 10**9 + first.header.stamp.nanosec == rec.imu_stamp_ns[0]
    assert first.linear_acceleration.x == rec.imu[0, 3]
    assert first.linear_acceleration_covariance[0] == 0.04
    assert first.orientation_covariance[0] == -1.0
    np.testing.assert_allclose(np.diag(np.reshape(first.angular_velocity_covariance, (3, 3))),
                               [1e-4, 4e-4, 9e-4])
    assert h.attitude[-1].header.frame_id == 'world'
    assert h.attitude[-1].header.stamp == h.corrected[-1].header.stamp


def test_a_queued_burst_is_taken_in_one_callback_in_order(harness, model_file):
    """Issue 18: one executor wake per message cannot keep up at 1 kHz; a burst drains."""
    import time
    from denoise_imu_ros.runtime.node import DRAIN_MAX
    rec = load_imu(SAMPLE)
    h = harness()
    callbacks = []
    real = h.node._on_imu
    h.node._sub.callback = lambda msg: (callbacks.append(1), real(msg))
    n = 40
    for t, r in zip(rec.imu_stamp_ns[:n], rec.imu[:n]):
        h.pub.publish(imu_msg(t, r[:3], r[3:]))
    time.sleep(1.0)  # all of them in the node's queue before its executor runs
    h.spin_until(lambda: h.processed() == n)
    assert len(callbacks) < n / 4 and n <= DRAIN_MAX  # a few wakes, not one per message
    h.spin_until(lambda: len(h.corrected) == n)
    assert [m.header.stamp for m in h.corrected] == [imu_msg(t, r[:3], r[3:]).header.stamp
                                                     for t, r in zip(rec.imu_stamp_ns[:n],
                                                                     rec.imu[:n])]
    got = np.array([[m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z]
                    for m in h.corrected])
    np.testing.assert_allclose(got, correct_gyro(load_model(model_file).model, rec.imu[:n]),
                               atol=1e-6)


@pytest.mark.parametrize('accel_bias', ['model', False])  # -p fusion_accel_bias:=off
def test_imu_data_is_the_imu_tools_contract_with_the_fused_orientation(
        harness, model_file, accel_bias):
    """imu/data: header copied, VQF orientation with its covariance, corrected gyro."""
    from denoise_imu_ros.core.modelfile import add_metadata
    from denoise_imu_ros.pipeline.fusion import fuse, FusionSettings, step_periods
    stored = FusionSettings(3.0, False, (0.02, -0.1, 0.05))  # the node overrides tau_acc
    add_metadata(model_file, fusion={'settings': stored.as_dict()})
    rec = load_imu(SAMPLE)
    n = 600
    h = harness(fusion_tau_acc=5.0, fusion_accel_bias=accel_bias)
    h.send([imu_msg(t, r[:3], r[3:]) for t, r in zip(rec.imu_stamp_ns[:n], rec.imu[:n])])
    assert len(h.fused) == n
    gyro = np.array([[m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z]
                     for m in h.fused])
    assert np.array_equal(gyro, np.array([[m.angular_velocity.x, m.angular_velocity.y,
                                           m.angular_velocity.z] for m in h.corrected]))
    quat = np.array([[m.orientation.x, m.orientation.y, m.orientation.z, m.orientation.w]
                     for m in h.fused])
    removed = stored.accel_bias_m_s2 if accel_bias == 'model' else (0.0, 0.0, 0.0)
    np.testing.assert_array_equal(quat, fuse(gyro, rec.imu[:n, 3:], 200.0, FusionSettings(
        5.0, False, removed), step_periods(rec.imu_stamp_ns[:n], 200.0)))
    for topic in (h.fused, h.corrected):  # less the bias the filter removes (a VIO's too)
        accel = [[m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z]
                 for m in topic]
        np.testing.assert_array_equal(accel, rec.imu[:n, 3:] - np.array(removed))
    first = h.fused[0]
    assert first.header == h.corrected[0].header
    assert first.linear_acceleration_covariance[0] == 0.04
    np.testing.assert_allclose(np.diag(np.reshape(first.orientation_covariance, (3, 3))),
                               [0.05 ** 2] * 3)  # the model file stores no fused figures


@pytest.mark.parametrize('value, estimated, accel', [
    ('model', True, 'model'), (False, False, 'off'), ('off', False, False), (True, True, 'model')])
def test_the_filter_switches_take_the_model_file_or_a_switch(harness, model_file, value,
                                                             estimated, accel):
    from denoise_imu_ros.core.modelfile import add_metadata
    from denoise_imu_ros.pipeline.fusion import FusionSettings
    stored = FusionSettings(3.0, True, (0.02, -0.1, 0.05))  # not the defaults, either of them
    add_metadata(model_file, fusion={'settings': stored.as_dict()})
    h = harness(fusion_bias_estimation=value, fusion_accel_bias=accel)
    settings = h.node._denoiser.fusion.settings
    assert settings.bias_estimation is estimated
    removed = stored.accel_bias_m_s2 if accel == 'model' else (0.0,) * 3
    assert settings.accel_bias_m_s2 == removed
    assert h.node._denoiser.accel_bias == removed  # imu/attitude's initial tilt too
    unfused = harness(publish_fused=False, fusion_accel_bias=accel)  # with imu/data off too
    assert unfused.node._denoiser.fusion is None and unfused.node._denoiser.accel_bias == removed


def test_imu_data_can_be_turned_off(harness):
    h = harness(publish_fused=False)
    assert h.node.count_publishers('imu/data') == 0 and h.node._pub_fused is None
    assert h.node.count_publishers('imu/corrected') == 1


def test_fuzz_two_thousand_messages_with_garbage(harness):
    rng = np.random.default_rng(7)
    h = harness()
    t, msgs = 1_700_000_000 * 10**9, []
    for _ in range(2000):
        kind = rng.random()
        t += int(rng.choice([5_000_000, 5_000_000, 5_000_000, 0, -3_000_000, 40_000_000,
                             -2_000_000_000]))
        gyro, accel = rng.normal(size=3), rng.normal(size=3) + [0, 0, 9.8]
        if kind < 0.05:
            gyro[rng.integers(3)] = rng.choice([np.nan, np.inf, -np.inf])
        elif kind < 0.08:
            accel[rng.integers(3)] = np.nan
        elif kind < 0.10:
            gyro *= 1e30
        elif kind < 0.16:  # extreme finite values over the whole float64 range
            (gyro if kind < 0.13 else accel)[rng.integers(3)] = rng.choice(
                [1.8e308, -1.8e308, 5e38, 3.4e38, -1e20, 5e-324, -0.0, 1e-310])
        stamp = 0 if kind > 0.98 else max(t, 0)
        msgs.append(imu_msg(stamp, gyro, accel))
    h.send(msgs)
    counts = h.node._denoiser.counts
    dropped = sum(counts[c] for c in DROP_CAUSES)
    assert counts['accepted'] + dropped == 2000
    assert counts['out_of_range'] > 20
    assert len(h.corrected) == counts['accepted'] > 1000
    for m in h.corrected:
        assert np.isfinite([m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z,
                            *m.angular_velocity_covariance]).all()
    for q in h.attitude:
        assert np.isfinite([q.quaternion.x, q.quaternion.y, q.quaternion.z, q.quaternion.w]).all()
    assert len(h.fused) == counts['accepted']
    for m in h.fused:
        o = m.orientation
        assert np.isfinite([o.x, o.y, o.z, o.w, *m.orientation_covariance]).all()
        assert abs(np.linalg.norm([o.x, o.y, o.z, o.w]) - 1) < 1e-9
    stamps = [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for m in h.corrected]
    resets = counts['time_jump_resets']
    assert sum(np.diff(stamps) <= 0) == resets  # increasing, except after a declared reset


def test_rate_mismatch_is_a_diagnostics_error(harness):
    h = harness()
    rec = load_imu(SAMPLE)
    stamps = rec.imu_stamp_ns[0] + np.arange(600) * 10_000_000  # 100 Hz into a 200 Hz model
    h.send([imu_msg(t, r[:3], r[3:]) for t, r in zip(stamps, rec.imu[:600])])
    h.spin_until(lambda: any(s.level == DiagnosticStatus.ERROR
                             for d in h.diagnostics for s in d.status), timeout=5.0)
    status = [s for d in h.diagnostics for s in d.status if s.level == DiagnosticStatus.ERROR][0]
    assert 'input rate 100.0 Hz differs from the model rate 200.0 Hz' in status.message
    assert {kv.key for kv in status.values} >= {'input_rate_hz', 'buffer_fill', 'accepted',
                                                'out_of_order', 'callback_time_p50_us',
                                                'skipped_periods', 'attitude_withheld'}
    assert status.name == '/gyro_denoiser: gyro correction'  # the namespaced node name
    assert status.hardware_id == 'imu4'  # the device: its messages' frame_id
    assert 'imu/corrected, imu/attitude and imu/data not published' in status.message
    # from now on no correction made at the wrong rate is published as if valid
    before = len(h.attitude), len(h.corrected), len(h.fused)
    later = stamps[-1] + np.arange(1, 201) * 10_000_000
    h.send([imu_msg(t, r[:3], r[3:]) for t, r in zip(later, rec.imu[600:800])])
    assert (len(h.attitude), len(h.corrected), len(h.fused)) == before
    assert h.node.corrected_withheld == 800 - before[1]


def test_an_input_that_stops_is_a_diagnostics_error(harness):
    h = harness()
    h.send([imu_msg(10**9 + k * 5_000_000, [0, 0, 0], [0, 0, 9.81]) for k in range(400)])
    h.diagnostics.clear()
    h.spin_until(lambda: h.diagnostics, timeout=5.0)
    assert h.diagnostics[-1].status[0].level != DiagnosticStatus.ERROR
    h.spin_until(lambda: any(s.level == DiagnosticStatus.ERROR for d in h.diagnostics
                             for s in d.status), timeout=6.0)  # nothing sent since
    status = [s for d in h.diagnostics for s in d.status][-1]
    values = {kv.key: kv.value for kv in status.values}
    assert status.message.startswith('no input for ') and status.message.endswith(
        ' s on /imu/data_raw')
    assert values['input_rate_hz'] == '0.00' and float(values['seconds_since_input']) > 2.0
    h.send([imu_msg(10**9 + k * 5_000_000, [0, 0, 0], [0, 0, 9.81]) for k in range(400, 800)])
    h.diagnostics.clear()
    h.spin_until(lambda: h.diagnostics, timeout=5.0)
    assert h.diagnostics[-1].status[0].level != DiagnosticStatus.ERROR  # flowing again


def test_rest_bias_on_estimates_the_turn_on_bias_of_a_still_start_and_says_so(harness):
    bias = [0.004, -0.003, 0.002]
    noise = np.random.default_rng(0).normal(0, 1e-3, (600, 3))
    h = harness(rest_bias='on')  # a model trained on the raw gyro: the defaults, prior 0
    h.send([imu_msg(10**9 + k * 5_000_000, bias + noise[k], [0, 0, 9.81]) for k in range(600)])
    h.diagnostics.clear()
    h.spin_until(lambda: h.diagnostics, timeout=5.0)
    values = {kv.key: kv.value for kv in h.diagnostics[-1].status[0].values}
    assert values['rest_bias_applied'] == 'True' and values['rest_bias_source'] == 'stillness'
    assert 2.0 < float(values['rest_bias_seconds_still']) <= 3.0
    np.testing.assert_allclose([float(v) for v in values['rest_bias_rad_s'].split()], bias,
                               atol=3e-4)
    assert 0 < float(values['rest_bias_sigma_rad_s']) < 1e-3
    off = harness(rest_bias='off')
    off.send([imu_msg(10**9 + k * 5_000_000, bias, [0, 0, 9.81]) for k in range(10)])
    off.spin_until(lambda: off.diagnostics, timeout=5.0)
    values = {kv.key: kv.value for kv in off.diagnostics[-1].status[0].values}
    assert values['rest_bias_applied'] == 'False' and 'rest_bias_rad_s' not in values


def test_one_long_gap_is_not_a_slow_stream(harness):
    h = harness()
    rec = load_imu(SAMPLE)
    stamps = rec.imu_stamp_ns[0] + np.arange(800) * 5_000_000
    stamps[400:] += 2_000_000_000  # 2 s without data, then the stream goes on
    h.send([imu_msg(t, r[:3], r[3:]) for t, r in zip(stamps, rec.imu[:800])])
    h.diagnostics.clear()
    h.spin_until(lambda: h.diagnostics, timeout=5.0)
    status = h.diagnostics[-1].status[0]
    values = {kv.key: kv.value for kv in status.values}
    assert float(values['input_rate_hz']) == pytest.approx(200.0, rel=0.01)
    assert status.level != DiagnosticStatus.ERROR
    assert values['gap_resets'] == '1' and values['skipped_periods'] == '400'
    assert values['attitude_withheld'] == '1'


def test_a_model_its_cross_recording_validation_advises_against_warns(model_file, harness):
    from denoise_imu_ros.core.modelfile import add_metadata
    add_metadata(model_file, crossval={'deploy': 'none', 'verdict': 'the network does not beat '
                                       'plain integration on unseen recordings (1 of 3, '
                                       '-61 % in mean AOE): deploy no correction'})
    h = harness()
    rec = load_imu(SAMPLE)
    h.send([imu_msg(t, r[:3], r[3:]) for t, r in zip(rec.imu_stamp_ns[:600], rec.imu[:600])])
    h.diagnostics.clear()
    h.spin_until(lambda: h.diagnostics, timeout=5.0)
    status = h.diagnostics[-1].status[0]
    assert status.level == DiagnosticStatus.WARN
    assert status.message == ('model.safetensors is a network model, but the cross-recording '
                              'validation of its recipe says: the network does not beat plain '
                              'integration on unseen recordings (1 of 3, -61 % in mean AOE): '
                              'deploy no correction')
    assert len(h.corrected) == 600  # it still runs: the user decides


def test_reset_attitude_service_and_embedded_attitude(harness):
    from scipy.spatial.transform import Rotation
    h = harness(embed_attitude=True, orientation_stddev=0.1)
    # one second of yaw at 1 rad/s: the attitude has turned by ~1 rad about z
    h.send([imu_msg(10**9 + k * 5_000_000, [0, 0, 1.0], [0, 0, 9.81]) for k in range(200)])
    turned = h.attitude[-1].quaternion
    assert abs(Rotation.from_quat([turned.x, turned.y, turned.z, turned.w]).as_euler(
        'ZYX')[0]) > 0.5
    cli = h.client.create_client(Trigger, 'gyro_denoiser/reset_attitude')
    h.spin_until(cli.service_is_ready)
    future = cli.call_async(Trigger.Request())
    h.spin_until(future.done)
    assert future.result().success
    # the next sample's attitude comes from its accelerometer alone: level, yaw 0
    h.send([imu_msg(10**9 + 200 * 5_000_000, [0, 0, 1.0], [0, 0, 9.81])])
    assert h.corrected[-1].orientation_covariance[0] == pytest.approx(0.01)
    assert h.corrected[-1].orientation.w == pytest.approx(1.0)
    assert h.attitude[-1].quaternion.w == pytest.approx(1.0)
    # after a gap the attitude is held, not published: nor embedded as if it were valid
    h.send([imu_msg(10**9 + 300 * 5_000_000, [0, 0, 1.0], [0, 0, 9.81])])
    assert h.corrected[-1].orientation_covariance[0] == -1.0
    assert h.node.attitude_withheld == 1


def test_missing_or_corrupt_model_exits_non_zero_with_one_line(tmp_path, capsys):
    args = ['--ros-args', '-p', f'model:={tmp_path / "absent.safetensors"}']
    assert main(args) == 1
    assert 'absent.safetensors: no such model file' in capsys.readouterr().err
    (tmp_path / 'bad.safetensors').write_bytes(b'x' * 100)
    assert main(['--ros-args', '-p', f'model:={tmp_path / "bad.safetensors"}']) == 1
    assert 'bad.safetensors: corrupt' in capsys.readouterr().err
    save_model(tmp_path / 'norate.safetensors', untrained_model(), {})
    assert main(['--ros-args', '-p', f'model:={tmp_path / "norate.safetensors"}']) == 1
    assert 'norate.safetensors: model file has no valid sample rate' in capsys.readouterr().err


def test_launch_file_compiles_and_config_is_keyed_for_any_node_name():
    import yaml
    root = ROOT
    compile((root / 'launch' / 'denoiser.launch.py').read_text(), 'denoiser.launch.py', 'exec')
    config = yaml.safe_load((root / 'config' / 'gyro_denoiser.yaml').read_text())
    params = config['/**']['ros__parameters']
    assert params['model'] == 'euroc'
    # the declaration is the one source: the YAML and the README's table say the same
    assert params == NODE_PARAMETERS
    rows = re.findall(r'^\| `(\w+)` \| (`?[^|]*?`?) \|', (root / 'README.md').read_text(), re.M)
    table = {name: default.strip('`') for name, default in rows if name in NODE_PARAMETERS}
    assert list(table) == list(NODE_PARAMETERS)
    written = {name: str(v).lower() if isinstance(v, bool) else str(v)
               for name, v in NODE_PARAMETERS.items()}
    assert table == written


def test_use_sim_time_is_accepted(harness):
    h = harness(use_sim_time=True)
    assert h.node.get_parameter('use_sim_time').value is True
    h.send([imu_msg(10**9 + k * 5_000_000, [0, 0, 0], [0, 0, 9.81]) for k in range(3)])
    assert len(h.corrected) == 3


def test_without_clock_diagnostics_and_the_rate_check_still_run(harness):
    """Use_sim_time and no /clock (a bag played without --clock)."""
    h = harness(use_sim_time=True)
    h.send([imu_msg(10**9 + k * 2_500_000, [0, 0, 0], [0, 0, 9.81]) for k in range(400)])
    h.spin_until(lambda: any(s.level == DiagnosticStatus.ERROR for d in h.diagnostics
                             for s in d.status), timeout=5.0)  # 400 Hz into a 200 Hz model
    h.send([imu_msg(10**9 + (400 + k) * 2_500_000, [0, 0, 0], [0, 0, 9.81])
            for k in range(10)])
    assert h.node.attitude_withheld >= 10 and h.node.fused_withheld >= 10


def test_qos_is_overridable_through_parameters(harness):
    h = harness(**{'qos_overrides./imu/corrected.publisher.reliability': 'best_effort',
                   'qos_overrides./imu/corrected.publisher.depth': 7})
    assert h.node._pub_imu.qos_profile.reliability == ReliabilityPolicy.BEST_EFFORT
    assert h.node._pub_imu.qos_profile.depth == 7


def test_ctrl_c_during_start_up_ends_the_node_cleanly(tmp_path, model_file):
    """A SIGINT after the node is built but before it spins: exit 0, no traceback."""
    script = tmp_path / 'race.py'
    script.write_text(f"""
import os, signal, sys
from denoise_imu_ros.runtime import node
built = node.GyroDenoiser.__init__
def init(self, **kwargs):
    built(self, **kwargs)
    os.kill(os.getpid(), signal.SIGINT)  # rclpy's handler shuts its context down
node.GyroDenoiser.__init__ = init
sys.exit(node.main(['--ros-args', '-p', 'model:={model_file}']))
""")
    import subprocess
    import sys
    run = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                         timeout=120, env=dict(os.environ, ROS_DOMAIN_ID=str(DOMAIN)))
    assert run.returncode == 0 and 'Traceback' not in run.stderr, run.stderr


def test_a_ctrl_c_landing_while_its_shutdown_is_handled_ends_cleanly(tmp_path, model_file):
    """Python's KeyboardInterrupt arriving inside the handler of rclpy's shutdown: exit 0."""
    script = tmp_path / 'race.py'
    script.write_text(f"""
import sys
import rclpy
from rclpy._rclpy_pybind11 import RCLError
from denoise_imu_ros.runtime import node
class Executor:  # the context a signal shut down: no guard condition can be made
    def __init__(self):
        rclpy.try_shutdown()
        raise RCLError('failed to create guard_condition: the given context is not valid')
def ok(*args, **kwargs):  # where Python's own SIGINT handler lands next
    raise KeyboardInterrupt
node.SingleThreadedExecutor = Executor
node.rclpy.ok = ok
sys.exit(node.main(['--ros-args', '-p', 'model:={model_file}']))
""")
    import subprocess
    import sys
    run = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                         timeout=120, env=dict(os.environ, ROS_DOMAIN_ID=str(DOMAIN)))
    assert run.returncode == 0 and 'Traceback' not in run.stderr, run.stderr


def test_the_node_needs_no_torch_and_equals_the_batch_network(tmp_path):
    # torch made unimportable: the node starts with the shipped model, and every message
    # through its callback gives the batch network's output (computed here, with torch)
    rec = load_imu(SAMPLE)
    n = 1500
    np.savez(tmp_path / 'data.npz', stamps=rec.imu_stamp_ns[:n], imu=rec.imu[:n],
             batch=correct_gyro(load_model('euroc').model, rec.imu[:n]))
    script = tmp_path / 'run.py'
    script.write_text(f"""
import sys


class NoTorch:
    def find_spec(self, name, path=None, target=None):
        if name == 'torch' or name.startswith('torch.'):
            raise ImportError('torch is not installed here')


sys.meta_path.insert(0, NoTorch())
import numpy as np
import rclpy
from rclpy.parameter import Parameter
from denoise_imu_ros.core import msgs
from denoise_imu_ros.runtime.node import GyroDenoiser
rclpy.init(domain_id={DOMAIN})
node = GyroDenoiser(parameter_overrides=[Parameter('model', value='euroc')])
sent = []  # what the callback publishes (one message refilled: its values, as serialised)
node._outputs.send_corrected = lambda m: sent.append(
    [m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z])
data = np.load({str(tmp_path / 'data.npz')!r})
types = msgs.rclpy_types()
for t, row in zip(data['stamps'], data['imu']):
    node._on_imu(msgs.imu(types, msgs.header(types, int(t), 'imu0'), row[:3], row[3:]))
out = np.array(sent)
assert len(out) == len(data['batch']), len(out)
print('max difference', np.abs(out - data['batch']).max())
assert np.abs(out - data['batch']).max() <= 1e-6
node.destroy_node()
rclpy.shutdown()
assert 'torch' not in sys.modules and 'safetensors.torch' not in sys.modules
print('ok')
""")
    import subprocess
    import sys
    run = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip().endswith('ok')


@pytest.mark.parametrize('args, message', [
    (['-p', 'max_gap_factor:=5'], "parameter 'max_gap_factor'"),
    (['-p', 'max_gap_factor:=0.5'], 'max_gap_factor out of range'),
    (['-p', 'input_queue_depth:=5'], 'input_queue_depth out of range'),
    (['-p', 'model:=5'], "parameter 'model'"),
    (['-p', 'embed_attitude:=maybe'], "parameter 'embed_attitude'"),
    (['-p', 'fusion_bias_estimation:=maybe'], "fusion_bias_estimation must be 'model', on"),
    (['-p', 'fusion_bias_estimation:=3'], "fusion_bias_estimation must be 'model', on"),
    (['-p', 'fusion_tau_acc:=-5.0'], 'fusion_tau_acc out of range'),
    (['-p', 'fusion_tau_acc:=0.0'], 'fusion_tau_acc must be a time constant above 0 s'),
    (['-p', 'fusion_accel_bias:=on'], "fusion_accel_bias must be 'model' or off, not on"),
    (['-p', 'rest_bias:=sometimes'], "rest_bias must be 'model', on or off, not 'sometimes'"),
    (['-p', 'envelope_guard:=on'], "envelope_guard must be 'model' or off, not on"),
    (['-p', 'qos_overrides./imu/corrected.publisher.reliability:=sometimes'],
     'a qos_overrides value rclpy cannot use (Unexpected QoS override for policy'),
    (['-p', 'qos_overrides./imu/data_raw.subscription.depth:=-5'],
     'qos_overrides./imu/data_raw.subscription.depth must be a positive integer, not -5'),
    (['-p', "qos_overrides./imu/data_raw.subscription.depth:='10'"],
     'a qos_overrides value rclpy cannot use (Trying to set parameter'),
    (['-p', "fixed_frame:=''"], 'fixed_frame must name a frame'),
])
def test_a_bad_parameter_is_a_one_line_error_at_start_up(args, message, capsys):
    assert main(['--ros-args', *args]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith('gyro_denoiser: error: bad parameter') and message in err
    assert len(err.splitlines()) == 1


def test_a_params_file_with_an_int_for_a_double_is_refused(tmp_path, capsys):
    (tmp_path / 'p.yaml').write_text('/**:\n  ros__parameters:\n    max_gap_factor: 3\n')
    assert main(['--ros-args', '--params-file', str(tmp_path / 'p.yaml')]) == 1
    err = capsys.readouterr().err
    assert "parameter 'max_gap_factor'" in err and 'with a point: max_gap_factor:=3.0' in err


def test_a_missing_or_malformed_params_file_is_a_one_line_error(tmp_path, capsys):
    (tmp_path / 'bad.yaml').write_text('x: [\n')
    for name in ('missing.yaml', 'bad.yaml'):
        assert main(['--ros-args', '--params-file', str(tmp_path / name)]) == 1
        err = capsys.readouterr().err.strip()
        assert err.startswith("gyro_denoiser: error: Failed to parse ROS arguments: Couldn't "
                              'parse params file') and name in err
        assert len(err.splitlines()) == 1 and not re.search(r'\.c:\d+', err)  # rcl's files


def test_a_misspelt_parameter_is_named_not_silently_ignored(harness):
    h = harness(modle='tumvi', max_gap_factor=4.0)
    assert h.node.unknown_parameters == ['modle']
    qos = harness(**{'qos_overrides./imu/corrected.publisher.depth': 50})
    assert qos.node.unknown_parameters == []  # QoS overrides are the node's own


def test_help_and_unknown_arguments(capsys):
    assert main(['--help']) == 0
    out = capsys.readouterr().out
    assert out.startswith('usage: gyro_denoiser') and 'max_gap_factor' in out
    assert main(['--model', 'tumvi']) == 1
    assert "unknown arguments '--model tumvi'" in capsys.readouterr().err


def test_every_message_dropped_is_an_error_naming_the_cause(harness):
    """Every stamp zero is not 'no input yet'."""
    h = harness()
    h.send([imu_msg(0, [0, 0, 0], [0, 0, 9.81]) for _ in range(50)])
    h.spin_until(lambda: any(s.level == DiagnosticStatus.ERROR for d in h.diagnostics
                             for s in d.status), timeout=3.0)
    status = [s for d in h.diagnostics for s in d.status][-1]
    assert status.message == 'no message accepted: dropped 50 (zero stamp)'


def test_a_rate_change_withholds_the_attitude_within_ten_samples(harness):
    """200 -> 100 Hz; not 2.3 s of attitudes published as valid."""
    h = harness()
    stamps = [10**9 + k * 5_000_000 for k in range(600)]
    stamps += [stamps[-1] + k * 10_000_000 for k in range(1, 101)]
    h.send([imu_msg(t, [0, 0, 0.1], [0, 0, 9.81]) for t in stamps])
    assert len(h.attitude) == 600 + 9 and h.node.attitude_withheld == 91
    assert len(h.fused) == 600 + 9


def test_a_params_file_for_another_node_and_a_namesake_are_said(tmp_path, harness):
    """A params file keyed to another node is dropped by rcl, and two nodes may share a name."""
    from denoise_imu_ros.runtime.node import foreign_params_files
    files = {'other.yaml': '/other_node:\n  ros__parameters: {model: tumvi}\n',
             'any.yaml': '/**:\n  ros__parameters: {model: tumvi}\n',
             'ns.yaml': '/robot/*:\n  ros__parameters: {model: tumvi}\n',
             'mine.yaml': 'gyro_denoiser:\n  ros__parameters: {model: tumvi}\n'}
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    args = ['--ros-args'] + [a for name in files for a in ('--params-file', str(tmp_path / name))]
    assert foreign_params_files(args, '/gyro_denoiser') == {
        str(tmp_path / 'other.yaml'): ['/other_node'], str(tmp_path / 'ns.yaml'): ['/robot/*']}
    assert foreign_params_files(args, '/robot/gyro_denoiser') == {
        str(tmp_path / 'other.yaml'): ['/other_node'], str(tmp_path / 'mine.yaml'):
        ['gyro_denoiser']}
    h = harness()
    assert h.node.namesakes == 0
    import rclpy
    twin = rclpy.create_node('gyro_denoiser', context=h.ctx)
    h.node._namesake_timer.reset()
    h.spin_until(lambda: h.node.namesakes == 1, timeout=5.0)
    twin.destroy_node()
