# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The network: the paper's size, its receptive field, causality, the calibration."""

from denoise_imu_ros.core.architecture import ModelConfig
from denoise_imu_ros.learn.model import Dropout, GyroNet
import torch


def test_paper_network_has_77052_trainable_parameters_and_receptive_field_511():
    model = GyroNet(ModelConfig())
    assert model.num_trainable() == 77052
    assert model.receptive_field == 511


def test_calibrated_imu_baseline_has_12_parameters():
    assert GyroNet(ModelConfig(calibration_only=True)).num_trainable() == 12


def test_output_depends_on_exactly_the_last_511_samples_and_never_the_future():
    torch.manual_seed(0)
    model = GyroNet(ModelConfig()).eval()
    u = torch.randn(1, 1500, 6)
    base = model(u)
    n = 1200
    future = u.clone()
    future[:, n + 1:] += torch.randn_like(future[:, n + 1:])
    assert torch.equal(model(future)[:, :n + 1], base[:, :n + 1])
    # the oldest sample inside the receptive field changes output n ...
    inside = u.clone()
    inside[:, n - 510] += 1.0
    assert not torch.allclose(model(inside)[:, n], base[:, n])
    # ... the one just outside does not
    outside = u.clone()
    outside[:, n - 511] += 1.0
    assert torch.equal(model(outside)[:, n], base[:, n])


def test_first_outputs_see_copies_of_the_first_sample():
    torch.manual_seed(1)
    model = GyroNet(ModelConfig()).eval()
    u = torch.randn(1, 600, 6)
    padded = torch.cat([u[:, :1].expand(1, 510, 6), u], dim=1)
    torch.testing.assert_close(model(u), model(padded)[:, 510:], rtol=0, atol=1e-6)


def test_untrained_network_at_identity_calibration_adds_gyro_std_scaled_correction():
    model = GyroNet(ModelConfig()).eval()
    u = torch.randn(2, 700, 6)
    expected = u[..., :3] + model.gyro_std * model.correction(u)
    torch.testing.assert_close(model(u), expected)
    assert torch.equal(model.delta, torch.zeros(3, 3))


def test_dropout_drops_the_requested_fraction_and_keeps_the_mean():
    torch.manual_seed(2)
    drop = Dropout(0.1).train()
    y = drop(torch.ones(1_000_000))
    assert abs((y == 0).float().mean().item() - 0.1) < 2e-3
    assert abs(y.mean().item() - 1.0) < 5e-3
    assert torch.equal(drop.eval()(torch.ones(10)), torch.ones(10))
