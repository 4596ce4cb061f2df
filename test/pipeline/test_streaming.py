# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The streaming engine (numpy and compiled steps) equals the batch network, from sample 1."""

from denoise_imu_ros.data.load import load_imu
from denoise_imu_ros.learn.model import correct_gyro
from denoise_imu_ros.pipeline.streaming import StreamingCorrector
from helpers import SAMPLE, untrained_model
import numpy as np
import pytest
import torch


@pytest.fixture(params=[False, True], ids=['numpy', 'compiled'])
def compiled(request):
    """Both steps: the compiled one must have been built (a compiler is part of CI)."""
    return request.param


@pytest.fixture(scope='module')
def imu():
    """Real EuRoC IMU samples (the bundled test-sequence sample)."""
    return load_imu(SAMPLE).imu


def _random_model(calibration_only=False):
    """Build an eval-mode network with non-trivial BatchNorm statistics and calibration."""
    model = untrained_model(calibration_only=calibration_only)
    with torch.no_grad():
        model.delta.normal_(std=0.01)
        for mod in model.modules():
            if isinstance(mod, torch.nn.BatchNorm1d):
                mod.running_mean.normal_()
                mod.running_var.uniform_(0.5, 2.0)
                mod.weight.normal_()
                mod.bias.normal_()
            if calibration_only:
                model.bias.normal_()
    return model


@pytest.mark.parametrize('calibration_only', [False, True])
def test_streaming_equals_batch_including_the_first_510_samples(
        imu, calibration_only, compiled):
    model = _random_model(calibration_only)
    batch = correct_gyro(model, imu[:3000])  # past every history's compaction
    stream = StreamingCorrector.from_module(model, compiled)
    assert stream.compiled == (compiled and not calibration_only)
    np.testing.assert_allclose(stream.process(imu[:3000]), batch, rtol=0, atol=1e-6)


def test_reset_starts_a_new_recording(imu, compiled):
    model = _random_model()
    stream = StreamingCorrector.from_module(model, compiled)
    stream.process(imu[:1000])
    stream.reset()
    np.testing.assert_allclose(stream.process(imu[2000:2800]), correct_gyro(model, imu[2000:2800]),
                               rtol=0, atol=1e-6)


def test_outputs_never_depend_on_future_samples(imu, compiled):
    stream = StreamingCorrector.from_module(_random_model(), compiled)
    first = stream.process(imu[:700])
    stream.reset()
    changed = imu[:800].copy()
    changed[700:] += 5.0
    assert np.array_equal(stream.process(changed)[:700], first)


def test_an_ensemble_is_the_mean_of_its_members_in_batch_and_streaming(imu, compiled):
    from denoise_imu_ros.learn.model import merge
    members = []
    for seed in range(3):
        member = _random_model()
        torch.manual_seed(seed + 10)  # members differ in every weight and in Delta
        with torch.no_grad():
            member.delta.normal_(std=0.01)
            member.input_mean.add_(0.1 * torch.randn(6))  # each its own normalisation
            member.input_std.mul_(1 + 0.1 * torch.rand(6))
            for mod in member.modules():
                if isinstance(mod, torch.nn.Conv1d):
                    mod.weight.normal_(std=0.05)
        members.append(member)
    ensemble = merge(members)
    mean = np.mean([correct_gyro(m, imu[:1500]) for m in members], axis=0)
    batch = correct_gyro(ensemble, imu[:1500])
    # the members do differ ...
    assert np.abs(np.array([correct_gyro(m, imu[:1500]) for m in members]) - mean).max() > 1e-3
    np.testing.assert_allclose(batch, mean, rtol=0, atol=1e-6)  # ... and average exactly
    np.testing.assert_allclose(StreamingCorrector.from_module(ensemble, compiled).process(
        imu[:1500]), batch, rtol=0, atol=1e-6)


def test_the_engine_gelu_is_the_exact_erf_gelu_to_float32_precision():
    from denoise_imu_ros.pipeline.streaming import _gelu
    from scipy.special import ndtr
    x = np.linspace(-20, 20, 400001)
    exact = x * ndtr(x)
    got = _gelu(x.astype(np.float32)).astype(np.float64)
    inside = x > -10
    assert np.abs(got - exact)[inside].max() < 2e-6 * 20  # float32 rounding of x itself
    assert np.abs(_gelu(x.copy()) - exact)[inside].max() < 3e-7  # the table, in float64
    assert (got[~inside] == 0).all()  # no denormal tail


def test_a_calibration_counts_its_samples_so_the_node_reports_it_warm():
    model = untrained_model(calibration_only=True)
    engine = StreamingCorrector.from_module(model)
    engine.step(np.zeros(6))
    assert engine.samples == 1 and engine.receptive_field == 1
