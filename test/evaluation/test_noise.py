# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Noise figures: the Allan fit recovers known noise, separates the poses' own noise."""

from denoise_imu_ros.evaluation.noise import covariance_check, figures, pooled, yaml_snippet
import numpy as np
import pytest
import yaml


def test_the_fit_recovers_white_noise_and_random_walk_and_keeps_pose_noise_apart():
    rate, n = 200.0, 200 * 600
    rng = np.random.default_rng(0)
    density, walk, angle = 2e-4, 2e-5, 1e-4   # rad/s/sqrt(Hz), rad/s^2/sqrt(Hz), rad
    white = rng.normal(0, density * np.sqrt(rate), (n, 3))
    drift = np.cumsum(rng.normal(0, walk / np.sqrt(rate), (n, 3)), axis=0)
    poses = np.diff(rng.normal(0, angle, (n + 1, 3)), axis=0) * rate  # differentiated angles
    fig = figures(white + drift + poses, rate)
    assert abs(fig['gyroscope_noise_density'] / density - 1) < 0.2
    assert 0.5 < fig['gyroscope_random_walk'] / walk < 2.0 and not fig['random_walk_is_bound']
    assert all(abs(a['angle_noise_rad'] / angle - 1) < 0.2 for a in fig['per_axis'])
    raw = dict(fig, gyroscope_noise_density=5e-3, gyroscope_random_walk=7e-4)
    snippet = yaml_snippet({'raw': raw, 'corrected': fig}, 'a test')
    pasted = yaml.safe_load(snippet)  # one document: the corrected gyro's keys, once each
    keys = [line.split(':')[0] for line in snippet.splitlines() if not line.startswith('#')]
    assert keys == ['gyroscope_noise_density', 'gyroscope_random_walk'] == list(pasted)
    assert abs(pasted['gyroscope_noise_density'] / density - 1) < 0.2
    assert '# gyroscope_noise_density: 5.000e-03' in snippet  # the raw one, a comment
    own = yaml_snippet({'corrected': fig}, 'a test', {'median': 1.2e-3, 'p95': 3.4e-3},
                       {'median': 5.6e-3, 'p95': 7.8e-3})
    assert yaml.safe_load(own) == yaml.safe_load(yaml_snippet({'corrected': fig}, 'a test'))
    said = 'variance per message (fit-variance) as a density: median 1.200e-03, 95th percentile'
    assert f'{said} 3.400e-03' in own  # a comment: the keys stay one density
    assert "accelerometer's: median 5.600e-03, 95th percentile 7.800e-03 m/s^2" in own


def test_a_random_walk_too_slow_to_resolve_is_an_upper_bound_not_zero():
    """A VIO told K = 0 takes the bias for a constant: the curve's bound, said to be one."""
    rate, n = 200.0, 200 * 120  # two minutes of the poses' angle noise: no +1/2 slope
    err = np.diff(np.random.default_rng(0).normal(0, 1e-4, (n + 1, 3)), axis=0) * rate
    fig = figures(err, rate)
    assert all(a['random_walk'] == 0.0 for a in fig['per_axis'])  # what the fit resolves
    taus, adev = np.array(fig['taus_s']), np.array(fig['adev_rad_s'])
    assert fig['random_walk_is_bound'] and fig['gyroscope_random_walk'] == pytest.approx(
        max(np.min(adev[:, i] * np.sqrt(3 / taus)) for i in range(3)))
    snippet = yaml_snippet({'corrected': fig}, 'a test')
    assert yaml.safe_load(snippet)['gyroscope_random_walk'] > 0
    assert 'an upper bound: the recordings are too short to resolve it' in snippet
    # pooled over recordings: a resolved figure wins over bounds (each above the IMU's K)
    resolved = dict(fig, gyroscope_random_walk=3e-5, random_walk_is_bound=False,
                    random_walk_resolved=3e-5)
    loose = dict(fig, gyroscope_random_walk=9e-5)
    both = pooled({'a': {'corrected': {'figures': loose}},
                   'b': {'corrected': {'figures': resolved}}})['corrected']
    assert both['gyroscope_random_walk'] == 3e-5 and not both['random_walk_is_bound']
    # one axis resolved under another's looser bound: the resolved one still counts
    mixed = dict(fig, gyroscope_random_walk=9e-5, random_walk_resolved=2e-5)
    assert pooled({'a': {'corrected': {'figures': mixed}}})['corrected'][
        'gyroscope_random_walk'] == 2e-5
    bounds = pooled({'a': {'corrected': {'figures': loose}},
                     'b': {'corrected': {'figures': fig}}})['corrected']
    assert bounds['random_walk_is_bound'] and bounds['gyroscope_random_walk'] == min(
        9e-5, fig['gyroscope_random_walk'])


def test_the_covariance_check_counts_samples_inside_one_two_three_sigma():
    err = np.random.default_rng(1).normal(0, [0.01, 0.02, 0.03], (100000, 3))
    check = covariance_check(err, np.array([0.01, 0.02, 0.03]))
    np.testing.assert_allclose(check['within_sigma'], [0.6827, 0.9545, 0.9973], atol=0.005)
    assert covariance_check(err, np.array([0.005, 0.01, 0.015]))['within_sigma'][0] < 0.4


def test_an_error_free_axis_has_zero_figures_not_a_traceback(tmp_path):
    """A synthetic recording whose gyro equals its poses' rate on an axis (noise, issue 20)."""
    from denoise_imu_ros.cli import main
    from helpers import write_asl, write_untrained_model
    err = np.zeros((4000, 3))
    err[:, 0] = np.random.default_rng(0).normal(0, 0.01, 4000)
    f = figures(err, 200.0)
    assert f['per_axis'][1]['noise_density'] == 0.0 and f['per_axis'][0]['noise_density'] > 0
    write_asl(tmp_path / 'rec', n_imu=3000)
    model = write_untrained_model(tmp_path / 'm.safetensors', {
        'sample_rate_hz': 200.0, 'gyro_variance': {'theta': [-9.0, 0.0, 0.0, 0.0]}})
    assert main(['noise', '--model', str(model), '--data', str(tmp_path), '--sequences', 'rec',
                 '--out', str(tmp_path / 'noise')]) == 0
    # the variance imu/corrected publishes per message, a constant here: its density
    density = f'{np.sqrt(np.exp(-9.0) / 200.0):.3e}'
    assert f'median {density}, 95th percentile {density}' in (
        tmp_path / 'noise' / 'noise.yaml').read_text()


def test_the_block_check_sees_white_noise_of_the_published_sigma_as_gaussian():
    """Mean rate errors over 16-sample increments of white noise: sigma / 4, 68/95/99.7 %."""
    rng = np.random.default_rng(3)
    std = np.array([0.01, 0.02, 0.03])
    per_sample = rng.normal(0, std, (64000, 3))
    blocks = per_sample.reshape(-1, 16, 3).mean(axis=1)
    check = covariance_check(per_sample, std, blocks)
    np.testing.assert_allclose(check['block_within_sigma'], [0.6827, 0.9545, 0.9973], atol=0.02)
    np.testing.assert_allclose(check['block_rms_over_sigma'], 1.0, atol=0.03)
    assert covariance_check(per_sample, 2 * std, blocks)['block_rms_over_sigma'][0] < 0.55
