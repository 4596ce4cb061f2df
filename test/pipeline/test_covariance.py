# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The outputs' variances per sample: per sample equal over arrays, reset with the network."""

from denoise_imu_ros.core.limits import GRAVITY_M_S2
from denoise_imu_ros.core.schema import SampleVariance
from denoise_imu_ros.pipeline.covariance import features, MAX_LOG_VARIANCE, Variance, variances
from denoise_imu_ros.pipeline.stages import Event, Flow, Pipeline, VarianceStage
import numpy as np
import pytest

SPEC = SampleVariance((-7.5, 1.5, 2.0, -1.5), 0.1, (0.1, 0.5, 1.0))
ACCEL = SampleVariance((-4.4, 0.6, 1.1, 0.1), 0.1, (0.1, 0.5, 1.0), (0.01, -0.02, 0.03))


def _motion(n: int = 3000, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = np.arange(n) / 200.0
    gyro = np.stack([np.sin(t), 2 * np.sin(3 * t), 0.1 * t], axis=1)
    gyro += rng.normal(0, 0.01, (n, 3))
    accel = np.array([0.0, 0.0, GRAVITY_M_S2]) + rng.normal(0, 1.0, (n, 3)) * (t > 5)[:, None]
    return gyro, accel


def test_the_pipeline_per_sample_equals_it_over_arrays_and_restarts_at_a_gap():
    gyro, accel = _motion()
    fed = np.hstack([gyro, accel])
    periods = np.ones(len(fed))
    periods[[0, 1700]] = 0.0  # the first sample, and one after a gap
    batch = Pipeline([VarianceStage(SPEC, 200.0, ACCEL)]).run(
        Flow(fed, dt_s=periods / 200.0, periods=periods, out=gyro))
    online, stage = Pipeline([VarianceStage(SPEC, 200.0, ACCEL)]), []
    for k in range(len(fed)):
        event = Event.START if k == 0 else Event.GAP if periods[k] == 0 else None
        flow = Flow(fed[k].copy(), event, 0.0, periods[k], out=gyro[k])
        online.step(flow, frozenset() if event is None else frozenset({event}))
        stage.append((flow.variance, flow.accel_variance))
    np.testing.assert_allclose(stage, np.stack([batch.variance, batch.accel_variance], axis=1),
                               rtol=1e-9)
    for spec, found in ((SPEC, batch.variance), (ACCEL, batch.accel_variance)):
        # after the gap the means start again: as a recording of its own
        np.testing.assert_allclose(found[1700:], variances(gyro[1700:], accel[1700:], 200.0,
                                                           spec), rtol=1e-12)
        assert not np.allclose(found[1700:1720], variances(gyro, accel, 200.0, spec)[1700:1720])
    gyro_only = Pipeline([VarianceStage(SPEC, 200.0)]).run(
        Flow(fed, dt_s=periods / 200.0, periods=periods, out=gyro))
    np.testing.assert_array_equal(gyro_only.variance, batch.variance)
    assert gyro_only.accel_variance is None


def test_the_variance_is_its_intercept_at_rest_and_grows_with_the_motion_as_theta_says():
    still = np.zeros((400, 3)), np.tile([0.0, 0.0, GRAVITY_M_S2], (400, 1))
    np.testing.assert_allclose(variances(*still, 200.0, SPEC), np.exp(-7.5), rtol=1e-12)
    phi = features(*_motion(), 200.0, SPEC)
    assert phi.shape == (3000, 4) and (phi[:, 0] == 1).all() and (phi[:, 1:] >= 0).all()
    spinning = np.tile([0.0, 0.0, 1.0], (400, 1)), still[1]  # 1 rad/s, steady
    assert variances(*spinning, 200.0, SPEC)[-1] == pytest.approx(
        np.exp(-7.5 + 1.5 * np.log1p(1.0 / 0.1)), rel=1e-12)


@pytest.mark.parametrize('entry, said', [
    ({'theta': [1.0, 2.0]}, 'theta must be four numbers'),
    ({'theta': [1.0, 2.0, 3.0, float('nan')]}, 'theta must be four numbers'),
    ({'theta': [0, 0, 0, 0], 'mean_s': 0}, 'mean_s must be a number of seconds'),
    ({'theta': [0, 0, 0, 0], 'scales': [1, 0, 1]}, 'scales must be three positive numbers'),
    ({'theta': [0, 0, 0, 0], 'sigma': 1}, "unknown entries \\['sigma'\\]")])
def test_a_variance_model_that_is_none_is_refused_in_one_line(entry, said):
    from denoise_imu_ros.core.errors import ModelFileError
    from denoise_imu_ros.core.schema import parse_meta
    with pytest.raises(ModelFileError, match=f'x: .*{said}'):
        parse_meta({'gyro_variance': entry}, 'x')
    with pytest.raises(ModelFileError, match=f'x: .*{said}'):
        parse_meta({'gyro_variance': SPEC.as_dict(), 'accel_variance': entry}, 'x')


def test_a_glitch_gives_a_huge_but_finite_variance_on_both_paths():
    gyro, accel = _motion(400)
    gyro[200] = 1e12  # a glitch the model's motion features blow up on
    wild = SampleVariance((10.0, 99.0, 0.0, 0.0))
    batch = Pipeline([VarianceStage(wild, 200.0, wild)]).run(
        Flow(np.hstack([gyro, accel]), out=gyro))
    online = Variance(wild, 200.0, wild)
    stage = [online.update(g, a) for g, a in zip(gyro, accel)]
    assert np.isfinite(batch.variance).all() and np.isfinite(stage).all()
    np.testing.assert_allclose(np.array(stage)[:, 1], batch.accel_variance, rtol=1e-9)
    assert batch.variance.max() == np.exp(MAX_LOG_VARIANCE)


@pytest.mark.parametrize('gyro', [None, {'theta': [0, 0, 0, 0], 'mean_s': 0.2}])
def test_an_accelerometer_variance_without_the_gyros_features_is_refused(gyro):
    from denoise_imu_ros.core.errors import ModelFileError
    from denoise_imu_ros.core.schema import parse_meta
    entries = {'accel_variance': ACCEL.as_dict(), **({} if gyro is None else
                                                     {'gyro_variance': gyro})}
    with pytest.raises(ModelFileError, match='x: accel_variance needs a gyro_variance of the '
                       'same mean_s and scales'):
        parse_meta(entries, 'x')
    meta = parse_meta({'accel_variance': ACCEL.as_dict(), 'gyro_variance': SPEC.as_dict()}, 'x')
    assert meta.accel_variance == ACCEL and meta.gyro_variance == SPEC
    with pytest.raises(ModelFileError, match='x: .*accel_bias_m_s2 must be three numbers'):
        parse_meta({'gyro_variance': SPEC.as_dict(), 'accel_variance': dict(
            ACCEL.as_dict(), accel_bias_m_s2=[5.0, 0.0, 0.0])}, 'x')  # not an IMU's bias
    with pytest.raises(ModelFileError, match='x: accel_variance needs its accel_bias_m_s2'):
        parse_meta({'accel_variance': SPEC.as_dict(), 'gyro_variance': SPEC.as_dict()}, 'x')
    with pytest.raises(ValueError, match="not on the gyro's features"):
        Variance(SPEC, 200.0, SampleVariance(ACCEL.theta, 0.2))
