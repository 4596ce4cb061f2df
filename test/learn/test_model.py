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


def _gradients(model: GyroNet, u: torch.Tensor) -> tuple[torch.Tensor, dict]:
    """Output and parameter gradients of one backward pass of a squared-output loss."""
    model.zero_grad()
    out = model(u)
    out.square().sum().backward()
    return out.detach(), {k: p.grad.clone() for k, p in model.named_parameters()}


def test_bfloat16_training_keeps_float32_ends_and_float32_gradients_within_its_rounding():
    torch.manual_seed(0)
    model = GyroNet(ModelConfig(dropout=0.0)).train()
    u = 0.3 * torch.randn(2, 3000, 6)
    out32, grad32 = _gradients(model, u)
    model.train_dtype = torch.bfloat16
    out16, grad16 = _gradients(model, u)
    assert out16.dtype == torch.float32
    assert not torch.equal(out16, out32)  # the hidden layers did run in bfloat16
    assert (out16 - out32).abs().max() < 1e-2 * out32.abs().max()
    for key, g in grad32.items():
        if key.endswith('bias') and key != f'net.{len(model.net) - 1}.bias':
            continue  # a bias followed by BatchNorm: its gradient is rounding noise
        assert (grad16[key] - g).norm() < 3e-2 * g.norm(), key
        assert grad16[key].dtype == torch.float32


def test_bfloat16_is_for_training_only_evaluation_stays_float32():
    torch.manual_seed(1)
    model = GyroNet(ModelConfig()).eval()
    u = 0.3 * torch.randn(1, 1000, 6)
    before = model(u)
    model.train_dtype = torch.bfloat16
    assert torch.equal(model(u), before)


def test_dropout_keeps_the_type_it_is_given():
    drop = Dropout(0.1).train()
    for dtype in (torch.float32, torch.bfloat16):
        assert drop(torch.ones(1000, dtype=dtype)).dtype == dtype


def test_recentring_moves_each_convolutions_level_into_its_bias_and_changes_no_output():
    torch.manual_seed(3)
    model = GyroNet(ModelConfig(dropout=0.0))
    u = 0.3 * torch.randn(2, 2000, 6)
    model.train()(u)  # BatchNorm's running means now hold the levels
    for i in range(4):
        model.net[4 * i].bias.data += 5.0  # a level far above the spread
    model(u)
    before_train, before_eval = model.train()(u), model.eval()(u)
    model.recentre()
    for i in range(4):
        assert model.net[4 * i + 1].running_mean.abs().max() == 0
    torch.testing.assert_close(model.eval()(u), before_eval, rtol=0, atol=1e-6)
    torch.testing.assert_close(model.train()(u), before_train, rtol=0, atol=1e-6)
