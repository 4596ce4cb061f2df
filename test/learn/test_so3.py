# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Torch quaternion helpers against scipy, including at zero rotation."""

from denoise_imu_ros.learn.so3 import (prefix_product, quat_exp, quat_log, quat_mul,
                                       quat_rotate, tree_product)
import numpy as np
from scipy.spatial.transform import Rotation
import torch


def test_exp_mul_log_match_scipy():
    rng = np.random.default_rng(0)
    v = rng.normal(size=(100, 3)) * rng.choice([1e-9, 1e-3, 1.0], size=(100, 1))
    w = rng.normal(size=(100, 3))
    q = quat_exp(torch.tensor(v))
    dot = np.sum(q.numpy() * Rotation.from_rotvec(v).as_quat(), axis=1)
    np.testing.assert_allclose(np.abs(dot), 1.0, atol=1e-12)  # same rotation, unit norm
    pq = quat_mul(torch.tensor(Rotation.from_rotvec(w).as_quat()), q)
    expect = (Rotation.from_rotvec(w) * Rotation.from_rotvec(v)).as_rotvec()
    np.testing.assert_allclose(quat_log(pq).numpy(), expect, atol=1e-10)


def test_rotate_matches_scipy():
    rng = np.random.default_rng(2)
    r = Rotation.from_rotvec(rng.normal(size=(50, 3)))
    v = rng.normal(size=(50, 3))
    np.testing.assert_allclose(quat_rotate(torch.tensor(r.as_quat()), torch.tensor(v)).numpy(),
                               r.apply(v), atol=1e-12)


def test_tree_product_is_the_ordered_product():
    rng = np.random.default_rng(1)
    v = rng.normal(size=(2, 32, 3)) * 0.3
    tree = tree_product(quat_exp(torch.tensor(v)), 4).numpy()
    for b in range(2):
        for m in range(2):
            r = Rotation.identity()
            for k in range(16):
                r = r * Rotation.from_rotvec(v[b, 16 * m + k])
            np.testing.assert_allclose(Rotation.from_quat(tree[b, m]).as_rotvec(),
                                       r.as_rotvec(), atol=1e-12)


def test_gradients_are_finite_at_zero_rotation():
    v = torch.zeros(4, 3, dtype=torch.float64, requires_grad=True)
    quat_log(quat_exp(v)).sum().backward()
    assert torch.isfinite(v.grad).all()
    torch.testing.assert_close(v.grad, torch.ones_like(v))


def test_prefix_product_is_every_ordered_product_from_the_first():
    rng = np.random.default_rng(4)
    rot = Rotation.from_rotvec(rng.normal(scale=0.3, size=(2, 37, 3)).reshape(-1, 3))
    q = torch.tensor(rot.as_quat().reshape(2, 37, 4))
    got = prefix_product(q).numpy()
    assert got.shape == (2, 38, 4)
    for row in range(2):
        att = Rotation.identity()
        for k in range(38):
            assert min(np.abs(got[row, k] - att.as_quat()).max(),
                       np.abs(got[row, k] + att.as_quat()).max()) < 1e-12
            if k < 37:
                att = att * Rotation.from_quat(q[row, k].numpy())
    assert prefix_product(q[:, :0]).tolist() == [[[0.0, 0.0, 0.0, 1.0]]] * 2  # no step
