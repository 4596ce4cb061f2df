# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The increment loss: zero for the true rate, masks holes, sees every axis."""

from denoise_imu_ros.learn.loss import increment_loss, LossConfig
import numpy as np
import pytest
from scipy.spatial.transform import Rotation
import torch

T = 640


def _truth(seed=0):
    """Smooth attitude at T + 1 stamps and the exact rate that produces it."""
    rng = np.random.default_rng(seed)
    dt = np.full(T, 0.005) + rng.uniform(-1e-5, 1e-5, T)
    omega = np.cumsum(rng.normal(scale=0.05, size=(T, 3)), axis=0)
    r = [Rotation.from_rotvec(rng.normal(size=3))]
    for k in range(T):
        r.append(r[-1] * Rotation.from_rotvec(omega[k] * dt[k]))
    quat = Rotation.concatenate(r).as_quat()
    return (torch.tensor(omega)[None], torch.tensor(dt)[None], torch.tensor(quat)[None],
            torch.ones(1, T + 1, dtype=torch.bool))


def test_true_rate_gives_zero_loss_and_a_bias_on_any_single_axis_does_not():
    omega, dt, quat, valid = _truth()
    assert increment_loss(omega, dt, quat, valid).item() < 1e-12
    for axis in range(3):
        biased = omega.clone()
        biased[..., axis] += 0.01
        assert increment_loss(biased, dt, quat, valid).item() > 0.05


def test_heading_weight_scales_only_the_error_about_the_poses_vertical():
    omega, dt, quat, valid = _truth()
    body_from_world = Rotation.from_quat(quat[0, :-1].numpy()).inv()
    losses = {}
    for axis in (0, 2):  # a rate error about the world's x (tilt), then its z (heading)
        error = np.zeros(3)
        error[axis] = 0.01
        biased = omega + torch.tensor(body_from_world.apply(error))[None]
        losses[axis] = [increment_loss(biased, dt, quat, valid, LossConfig(heading_weight=w))
                        .item() for w in (1.0, 0.5, 0.0)]
    tilt, heading = losses[0], losses[2]
    assert tilt[0] == pytest.approx(increment_loss(omega + torch.tensor(
        body_from_world.apply([0.01, 0, 0]))[None], dt, quat, valid).item())  # 1: as before
    assert tilt[2] == pytest.approx(tilt[0], rel=0.05)   # the tilt error counts in full
    assert heading[1] == pytest.approx(0.25 * heading[0], rel=0.05)  # small: quadratic
    assert heading[2] < 1e-3 * heading[0]                # and not at all at 0


def test_ground_truth_holes_are_masked_in_both_terms():
    omega, dt, quat, valid = _truth()
    omega = omega + 0.002  # a real residual, so the masked mean is not trivially zero
    valid[:, 200:260] = False
    base = increment_loss(omega, dt, quat, valid)
    garbage = quat.clone()
    garbage[:, 205:255] = torch.tensor([1.0, 0.0, 0.0, 0.0], dtype=torch.float64)
    assert increment_loss(omega, dt, garbage, valid).item() == pytest.approx(base.item())
    valid_everywhere = torch.ones_like(valid)
    assert increment_loss(omega, dt, garbage, valid_everywhere).item() > 10 * base.item()


def test_skipped_warm_up_blocks_do_not_count():
    omega, dt, quat, valid = _truth()
    bad_start = omega.clone()
    bad_start[:, :80] += 1.0  # the first 5 blocks of 16 samples
    cfg = LossConfig()
    # level 16 skips samples < 80 and level 32 skips samples < 160: no effect at all
    assert increment_loss(bad_start, dt, quat, valid, cfg).item() < 1e-12
    assert increment_loss(bad_start, dt, quat, valid, LossConfig(skip_blocks=0)).item() > 1


def test_increment_terms_add_up_and_bad_lengths_are_refused():
    omega, dt, quat, valid = _truth()
    omega = omega + 0.003
    only16 = increment_loss(omega, dt, quat, valid, LossConfig(increments=(16,), weights=(1.0,)))
    only32 = increment_loss(omega, dt, quat, valid, LossConfig(increments=(32,), weights=(1.0,)))
    both = increment_loss(omega, dt, quat, valid)
    assert both.item() == pytest.approx(only16.item() + 0.5 * only32.item())
    long = increment_loss(omega, dt, quat, valid, LossConfig(increments=(64, 128),
                                                             weights=(1.0, 1.0), skip_blocks=0))
    assert long.item() > both.item()  # a bias error grows with the increment length
    for bad in [(16, 24), (32, 16), ()]:
        with pytest.raises(ValueError, match='powers of two'):
            LossConfig(increments=bad, weights=(1.0,) * len(bad))


def _between(cfg: LossConfig) -> LossConfig:
    """Return the same loss between poses."""
    return LossConfig(**{**cfg.__dict__, 'between_poses': True})


def test_between_poses_at_every_block_boundary_is_the_grid_loss():
    omega, dt, quat, valid = _truth()
    omega = omega + 0.003
    one = LossConfig(increments=(32,), weights=(1.0,))
    pose_at = torch.zeros_like(valid)
    pose_at[:, ::32] = True
    grid = increment_loss(omega, dt, quat, valid, one)
    assert increment_loss(omega, dt, quat, valid, _between(one),
                          pose_at=pose_at).item() == pytest.approx(grid.item(), rel=1e-9)
    with pytest.raises(ValueError, match='pose stamps'):
        increment_loss(omega, dt, quat, valid, _between(one))


def test_between_poses_compares_each_pose_with_the_first_one_long_enough_after():
    omega, dt, quat, valid = _truth(seed=2)
    rng = np.random.default_rng(3)
    stamps = np.cumsum(rng.integers(10, 60, size=40))
    stamps = stamps[stamps <= T]
    pose_at = torch.zeros_like(valid)
    pose_at[0, stamps] = True
    bias = torch.tensor([0.004, -0.002, 0.003], dtype=torch.float64)
    cfg = LossConfig(increments=(64,), weights=(1.0,), skip_blocks=1, huber_delta=1.0,
                     between_poses=True)
    got = increment_loss(omega + bias, dt, quat, valid, cfg, pose_at=pose_at).item()
    # the reference: scipy, pose by pose
    est = [Rotation.identity()]
    for w, h in zip((omega + bias)[0].numpy(), dt[0].numpy()):
        est.append(est[-1] * Rotation.from_rotvec(w * h))
    truth = Rotation.from_quat(quat[0].numpy())
    terms = []
    for a in stamps[stamps >= 64]:
        b = stamps[stamps >= a + 64]
        if len(b) and b[0] - a <= 128:
            err = ((est[a].inv() * est[b[0]]).inv() * (truth[a].inv() * truth[b[0]])).as_rotvec()
            terms.append(0.5 * err ** 2)  # Huber below its threshold
    assert len(terms) > 10
    assert got == pytest.approx(cfg.scale * np.sum(terms) / (3 * len(terms)), rel=1e-6)
    # the true rate gives zero, and samples before the first compared pose change nothing
    assert increment_loss(omega, dt, quat, valid, cfg, pose_at=pose_at).item() < 1e-12
    early = omega + bias
    early[:, :stamps[stamps >= 64][0]] += 1.0
    assert increment_loss(early, dt, quat, valid, cfg, pose_at=pose_at).item() == pytest.approx(
        got, rel=1e-9)


def test_between_poses_masks_holes_and_stretches():
    omega, dt, quat, valid = _truth()
    omega = omega + 0.002
    cfg = LossConfig(increments=(32,), weights=(1.0,), skip_blocks=0, between_poses=True)
    pose_at = torch.zeros_like(valid)
    pose_at[:, [0, 40, 100, 140, 300, 340]] = True  # 140 -> 300 is beyond twice 32 samples
    base = increment_loss(omega, dt, quat, valid, cfg, pose_at=pose_at)
    wrong = omega.clone()
    wrong[:, 141:300] += 1.0  # only inside the increment too long to count at 32 (at 128 not)
    assert increment_loss(wrong, dt, quat, valid, cfg,
                          pose_at=pose_at).item() == pytest.approx(base.item())
    longer = LossConfig(increments=(128,), weights=(1.0,), skip_blocks=0, between_poses=True)
    assert increment_loss(wrong, dt, quat, valid, longer, pose_at=pose_at).item() > 10 * (
        increment_loss(omega, dt, quat, valid, longer, pose_at=pose_at).item())
    valid[:, 20] = False  # inside the first increment: it no longer counts
    assert increment_loss(omega, dt, quat, valid, cfg, pose_at=pose_at).item() != pytest.approx(
        base.item())


def test_the_loss_compares_the_increments_check_data_and_training_find_between_poses():
    from denoise_imu_ros.core.metrics import increments
    from denoise_imu_ros.learn.loss import pose_increments
    rng = np.random.default_rng(7)
    pose_at = rng.random((3, 2001)) < 0.03
    valid = rng.random((3, 2001)) > 0.0005
    for length in (32, 64, 128):
        end, ok = pose_increments(torch.tensor(pose_at), torch.tensor(valid), length)
        for row in range(3):
            starts, ends = increments(valid[row], length, pose_at[row])
            found = np.flatnonzero(ok[row].numpy())
            assert len(found) > 5
            assert np.array_equal(found, starts)
            assert np.array_equal(end[row, found].numpy(), ends)
