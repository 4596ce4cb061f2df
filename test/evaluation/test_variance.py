# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""fit-variance: the likelihood's fit finds the variances the IMU's errors were drawn with."""

from denoise_imu_ros.core.limits import GRAVITY_M_S2
from denoise_imu_ros.core.metrics import integrate
from denoise_imu_ros.core.records import Sequence
from denoise_imu_ros.core.schema import SampleVariance
from denoise_imu_ros.evaluation.variance import fit, nees, Windows
from denoise_imu_ros.pipeline.covariance import features, variances
import numpy as np
import pytest

TRUE = SampleVariance((-8.0, 1.2, 0.0, 0.0))
RATE = 200.0


def _recording(seed: int, n: int = 24000, pose_noise_rad: float = 0.0
               ) -> tuple[Sequence, np.ndarray, np.ndarray]:
    """
    Poses of a true motion; a gyro whose white errors have TRUE's variance at each sample.

    Each pose turned by its own white noise of ``pose_noise_rad`` per axis.
    """
    from scipy.spatial.transform import Rotation
    rng = np.random.default_rng(seed)
    t = np.arange(n) / RATE
    rate = np.stack([np.sin(0.3 * t), np.cos(0.7 * t), 2.0 * np.sin(0.05 * t) ** 2], axis=1)
    accel = np.tile([0.0, 0.0, GRAVITY_M_S2], (n, 1))
    sigma = np.sqrt(variances(rate, accel, RATE, TRUE))  # the true rate's motion
    gyro = rate + sigma[:, None] * rng.normal(size=(n, 3))
    stamps = (1e9 + t * 1e9).astype(np.int64)
    quat = integrate(np.array([0.0, 0.0, 0.0, 1.0]), rate[:-1], np.diff(t))
    quat = (quat * Rotation.from_rotvec(pose_noise_rad * rng.normal(size=(n, 3)))).as_quat()
    seq = Sequence('s', stamps, np.hstack([gyro, accel]), quat, np.zeros((n, 3)),
                   np.ones(n, bool))
    return seq, gyro, accel


def _close(found: SampleVariance, true: SampleVariance, windows: list[Windows]) -> None:
    """Each sample's variance within 20 % of the one its errors were drawn with."""
    phi = np.vstack([w.phi for w in windows])
    ratio = np.exp(phi @ (np.array(found.theta) - np.array(true.theta)))
    assert 0.8 < np.percentile(ratio, 5) and np.percentile(ratio, 95) < 1.25


def test_the_fit_finds_the_variance_the_errors_were_drawn_with_and_its_nees_is_three():
    train = []
    for seed in range(3):
        seq, gyro, accel = _recording(seed)
        train.append(Windows.of(seq, gyro, features(gyro, accel, RATE, TRUE)))
    fitted = fit(train)
    found = fitted.variance
    _close(found, TRUE, train)
    each = fit(train, lengths_alike=False).variance  # every window weighing alike: the same
    _close(each, TRUE, train)
    assert np.degrees(np.sqrt(fitted.reference_var)) < 0.005  # exact poses: almost none
    seq, gyro, accel = _recording(7)  # another recording
    held = [Windows.of(seq, gyro, features(gyro, accel, RATE, found))]
    for window, row in nees(found, held).items():
        assert 2.7 < row['mean'] < 3.3, window
        assert 0.68 < row['in_2_sigma'] < 0.80, window
    one = SampleVariance((found.theta[0] + 2.0, *found.theta[1:]))  # 2.7 times too wide
    assert all(row['mean'] < 1.5 for row in nees(one, held).values())


def test_the_poses_own_noise_is_fitted_beside_the_gyros_and_counted_in_the_nees():
    noise = np.radians(0.1)  # per axis and pose: a window's ends hold twice its variance
    train = []
    for seed in range(3):
        seq, gyro, accel = _recording(seed, pose_noise_rad=noise)
        train.append(Windows.of(seq, gyro, features(gyro, accel, RATE, TRUE)))
    fitted = fit(train)
    _close(fitted.variance, TRUE, train)
    assert 0.8 < fitted.reference_var / (2 * noise ** 2) < 1.25
    seq, gyro, accel = _recording(7, pose_noise_rad=noise)
    held = [Windows.of(seq, gyro, features(gyro, accel, RATE, fitted.variance))]
    for window, row in nees(fitted.variance, held, fitted.reference_var).items():
        assert 2.7 < row['mean'] < 3.3, window
    # the gyro's variance alone, fitted as if the poses were exact, is too wide at 2 s
    alone = fit(train, reference_noise=False)
    assert alone.reference_var == 0.0
    assert nees(alone.variance, held)['2 s']['mean'] < 2.5


def _moving(seed: int, accel_true: SampleVariance, n: int = 24000
            ) -> tuple[Sequence, np.ndarray, np.ndarray, np.ndarray]:
    """
    Return a recording whose poses move; its accelerometer's white errors of that variance.

    The poses' velocities and positions are the true specific force integrated over each
    sample's interval as pre-integration takes it, so that only the errors are left.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(n) / RATE
    rate = np.stack([np.sin(0.3 * t), np.cos(0.7 * t), 0.5 * np.sin(0.05 * t)], axis=1)
    quat = integrate(np.array([0.0, 0.0, 0.0, 1.0]), rate[:-1], np.diff(t))
    world = np.stack([np.sin(0.5 * t), np.cos(0.9 * t), 0.3 * np.sin(1.3 * t)], axis=1)
    true = quat.inv().apply(world + [0.0, 0.0, GRAVITY_M_S2])  # specific force, body frame
    vel = np.concatenate([[[0.0, 0.0, 0.0]], np.cumsum(world[:-1] / RATE, axis=0)])
    pos = np.concatenate([[[0.0, 0.0, 0.0]], np.cumsum(
        vel[:-1] / RATE + 0.5 * world[:-1] / RATE ** 2, axis=0)])
    sigma = np.sqrt(variances(rate, true, RATE, accel_true))
    accel = true + sigma[:, None] * rng.normal(size=(n, 3))
    stamps = (1e9 + t * 1e9).astype(np.int64)
    seq = Sequence('s', stamps, np.hstack([rate, accel]), quat.as_quat(), pos, np.ones(n, bool))
    return seq, rate, accel, vel


def test_the_accelerometers_variance_is_found_from_the_velocity_increments():
    true = SampleVariance((-5.0, 1.0, 0.0, 0.0))
    train = []
    for seed in range(3):
        seq, gyro, accel, vel = _moving(seed, true)
        train.append(Windows.velocity(seq, gyro, accel, vel, features(gyro, accel, RATE, true)))
    fitted = fit(train)
    _close(fitted.variance, true, train)
    assert np.sqrt(fitted.reference_var) < 1e-3  # exact velocities: almost none
    seq, gyro, accel, vel = _moving(7, true)
    held = [Windows.velocity(seq, gyro, accel, vel, features(gyro, accel, RATE, true))]
    for window, row in nees(fitted.variance, held, fitted.reference_var).items():
        assert 2.7 < row['mean'] < 3.3, window


def test_fit_variance_fits_on_the_tails_stores_it_and_refuses_a_shipped_file(tmp_path, capsys):
    from denoise_imu_ros.cli import main
    from denoise_imu_ros.learn.checkpoint import load_model, save_model
    from helpers import SAMPLE, untrained_model
    model = tmp_path / 'm.safetensors'
    save_model(model, untrained_model(), {
        'sample_rate_hz': 200.0, 'train_sequences': [SAMPLE.name],
        'run': {'data': str(SAMPLE.parent)}, 'train_config': {'window': 16000}})
    assert main(['fit-variance', '--model', str(model), '--attach', '--quiet']) == 0
    out = capsys.readouterr().out
    assert 'validation tails of euroc_V1_03_90s (from sample 16000 on)' in out
    assert all(f'| {w} s |' in out for w in ('0.1', '0.2', '0.5', '1', '2'))
    assert 'accelerometer variance exp(theta . phi)' in out
    stored = load_model(str(model)).meta
    assert stored.gyro_variance is not None and stored.accel_variance is not None
    for key in ('gyro_variance', 'accel_variance'):
        assert set(stored.raw[key]['nees']) == {'0.1 s', '0.2 s', '0.5 s', '1 s', '2 s'}
    assert stored.raw['gyro_variance']['reference_noise_deg'] >= 0.0
    assert stored.raw['accel_variance']['reference_noise_m_s'] >= 0.0
    assert main(['fit-variance', '--model', 'euroc', '--attach']) == 1  # before any work
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and 'shipped' in err


def test_each_window_length_weighs_alike_and_the_gradient_is_the_likelihoods():
    from denoise_imu_ros.evaluation.variance import _nll
    seq, gyro, accel = _recording(0, n=6000)
    windows = [Windows.of(seq, gyro, features(gyro, accel, RATE, TRUE))]
    params = np.array([-7.6, 1.0, 0.2, -0.1, -18.0])
    value, grad = _nll(params, windows)
    alone = [_nll(params, [Windows(w.phi, w.dt2, [found])])[0]
             for w in windows for found in w.found]
    assert len(alone) == 5 and value == pytest.approx(np.mean(alone), rel=1e-12)
    every = _nll(params, windows, lengths_alike=False)[0]  # the 0.1 s windows outweigh
    counts = [len(starts) for _, starts, _, _ in windows[0].found]
    assert every == pytest.approx(np.dot(alone, counts) / sum(counts), rel=1e-12)
    for alike in (True, False):
        value, grad = _nll(params, windows, alike)
        step = 1e-6
        numeric = [(_nll(params + step * e, windows, alike)[0] - value) / step
                   for e in np.eye(5)]
        np.testing.assert_allclose(grad, numeric, rtol=1e-3, atol=1e-6)


def test_a_refit_without_positions_drops_the_accelerometers_old_variance(
        capsys, monkeypatch, model_file):
    from denoise_imu_ros.cli import main
    from denoise_imu_ros.core.modelfile import add_metadata, read_model_file
    from denoise_imu_ros.evaluation import variance
    gyro = {'theta': [-7.5, 1.5, 2.0, -1.5], 'nees': {}, 'held_out': {}, 'fitted_on': 'tails',
            'reference_noise_deg': 0.0}
    add_metadata(model_file, gyro_variance=gyro, accel_variance={
        'theta': [-4.4, 0.6, 1.1, 0.1], 'accel_bias_m_s2': [0.0, 0.0, 0.0]})
    monkeypatch.setattr(variance, 'fit_model', lambda *a, **k: {'gyro_variance': gyro})
    assert main(['fit-variance', '--model', str(model_file), '--attach', '--quiet']) == 0
    assert "accelerometer: no variance fitted (a recording's poses have no positions)" in (
        capsys.readouterr().out)
    meta = read_model_file(model_file).meta
    assert meta.accel_variance is None and meta.gyro_variance is not None
