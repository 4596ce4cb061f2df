# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The one publish/withhold policy and message builder the node and process-bag share."""

from denoise_imu_ros.core import msgs
from denoise_imu_ros.data.bags import BAG_TYPES
from denoise_imu_ros.pipeline.online import Event, Output
from denoise_imu_ros.runtime.outputs import Decision, Outputs, Withheld, withheld
import numpy as np
import pytest

OFF, GAP = Withheld.OFF_RATE, Withheld.GAP


def _output(event=None, rate_suspect=False):
    return Output(stamp_ns=10**9, gyro=np.array([0.1, 0.2, 0.3]), accel=np.array([0, 0, 9.7]),
                  attitude=np.array([0.0, 0.0, 0.6, 0.8]), event=event,
                  orientation=np.array([0.6, 0.0, 0.0, 0.8]), rate_suspect=rate_suspect,
                  accel_cov=np.zeros(9))


@pytest.mark.parametrize('event, suspect, decision', [
    (None, False, Decision(None, None, None)),
    (Event.START, False, Decision(None, None, None)),
    (Event.TIME_JUMP, False, Decision(None, None, None)),
    (Event.GAP, False, Decision(None, None, GAP)),
    (None, True, Decision(OFF, OFF, OFF)),
    (Event.GAP, True, Decision(OFF, OFF, OFF)),
])
def test_the_policy(event, suspect, decision):
    assert withheld(_output(event, suspect)) == decision


@pytest.mark.parametrize('embed', [False, True])
def test_what_is_sent_carries_the_raw_header_and_the_covariances_and_withheld_is_counted(embed):
    sent = {'corrected': [], 'fused': [], 'attitude': []}

    def keep(topic):  # a transport serialises at once: keep the values, not the object
        return lambda m: sent[topic].append(
            (m.header.stamp.sec, getattr(m, 'orientation_covariance', [None])[0],
             (m.orientation if topic != 'attitude' else m.quaternion).w))
    out = Outputs(BAG_TYPES, keep('corrected'), keep('fused'), keep('attitude'), 'odom',
                  np.eye(3).ravel() * 1e-4, np.eye(3).ravel() * 4e-4, embed,
                  np.eye(3).ravel() * 9e-4)
    raw = msgs.imu(BAG_TYPES, msgs.header(BAG_TYPES, 7 * 10**9, 'imu4'), [0, 0, 0], [0, 0, 9.8])
    out.send(raw, _output())
    out.send(raw, _output(Event.GAP))
    out.send(raw, _output(rate_suspect=True))
    assert [s[0] for s in sent['corrected']] == [7, 7]  # header copied, never re-stamped
    embedded = [s[1] for s in sent['corrected']]
    assert embedded == ([9e-4, -1.0] if embed else [-1.0, -1.0])  # not across the gap
    assert [s[1:] for s in sent['fused']] == [(4e-4, 0.8)] * 2  # the fused orientation
    assert sent['attitude'] == [(7, None, 0.8)]
    assert out.counts == {'corrected_withheld': 1, 'fused_withheld': 1, 'attitude_withheld': 2}
    off = Outputs(BAG_TYPES, keep('corrected'), None, keep('attitude'), 'odom', np.zeros(9),
                  np.zeros(9))
    off.send(raw, _output())  # imu/data off: nothing sent there, nothing counted
    assert len(sent['fused']) == 2 and off.counts['fused_withheld'] == 0


def test_the_accelerometer_covariance_is_each_samples_own_the_fixed_one_or_the_inputs():
    sent = []
    input_cov = np.eye(3).ravel() * 0.04
    out = Outputs(BAG_TYPES, lambda m: sent.append(np.array(m.linear_acceleration_covariance)),
                  None, lambda m: None, 'odom', np.zeros(9), np.zeros(9))
    raw = msgs.imu(BAG_TYPES, msgs.header(BAG_TYPES, 7 * 10**9, 'imu4'), [0, 0, 0], [0, 0, 9.8])
    sample = Output(stamp_ns=10**9, gyro=np.zeros(3), accel=np.array([0, 0, 9.7]),
                    attitude=np.array([0.0, 0.0, 0.0, 1.0]), event=None, accel_cov=input_cov,
                    gyro_var=1e-4, accel_var=2.5e-3)
    out.send(raw, sample)                  # neither a model's nor a fixed one: the input's
    out.per_sample_accel = True
    out.send(raw, sample)                  # the sample's own
    out.send(raw, sample._replace(accel_var=3.5e-3))
    out.send(raw, sample._replace(accel_var=None))  # a sample without one: the input's
    out.per_sample_accel, out.accel_cov = False, np.eye(3).ravel() * 0.01
    out.send(raw, sample)                  # the node's override
    np.testing.assert_array_equal(sent, [input_cov, np.eye(3).ravel() * 2.5e-3,
                                         np.eye(3).ravel() * 3.5e-3, input_cov,
                                         np.eye(3).ravel() * 0.01])
