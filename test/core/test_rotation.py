# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The hand-written rotation arithmetic (robot path, integration, alignment) equals scipy's."""

from denoise_imu_ros.core import rotation
import numpy as np
import pytest
from scipy.spatial.transform import Rotation


def _same(q, r: Rotation) -> float:
    return float((Rotation.from_quat(q).inv() * r).magnitude())


@pytest.mark.parametrize('scale', [0.0, 1e-12, 1e-9, 1e-6, 1e-3, 0.1, 1.0, 3.0])
def test_exp_equals_scipy_from_rotvec(scale):
    for v in np.random.default_rng(0).normal(size=(50, 3)) * scale:
        assert _same(rotation.exp(*v), Rotation.from_rotvec(v)) < 1e-12


def test_multiply_equals_scipy_composition_and_stays_unit():
    rng = np.random.default_rng(1)
    p, q = Rotation.random(200, random_state=2), Rotation.random(200, random_state=3)
    for a, b in zip(p.as_quat(), q.as_quat()):
        c = rotation.multiply(tuple(a), tuple(b))
        assert _same(c, Rotation.from_quat(a) * Rotation.from_quat(b)) < 1e-12
        assert abs(np.linalg.norm(c) - 1) < 1e-15
    # a long chain of small steps stays on the unit sphere and equals scipy's
    q, ref = (0.0, 0.0, 0.0, 1.0), Rotation.identity()
    for w in rng.normal(0, 0.01, (5000, 3)):
        q, ref = rotation.multiply(q, rotation.exp(*w)), ref * Rotation.from_rotvec(w)
    assert _same(q, ref) < 1e-9


def test_multiply_arrays_equals_scipy_composition_with_broadcasting():
    p, q = Rotation.random(300, random_state=5), Rotation.random(300, random_state=6)
    got = rotation.multiply_arrays(p.as_quat(), q.as_quat())
    assert (Rotation.from_quat(got).inv() * (p * q)).magnitude().max() < 1e-12
    assert np.abs(np.linalg.norm(got, axis=1) - 1).max() < 1e-15
    inverse = rotation.conjugate_arrays(p.as_quat())
    assert (Rotation.from_quat(inverse) * p).magnitude().max() < 1e-12
    one = rotation.multiply_arrays(p.as_quat()[0], q.as_quat().reshape(3, 100, 4))
    assert one.shape == (3, 100, 4)
    assert (Rotation.from_quat(one.reshape(-1, 4)).inv() * (p[0] * q)).magnitude().max() < 1e-12


def test_from_gravity_equals_scipy_euler():
    for roll, pitch in np.random.default_rng(4).uniform(-1.5, 1.5, (100, 2)):
        tilt = Rotation.from_euler('ZYX', [0.0, pitch, roll])
        accel = tilt.inv().apply([0.0, 0.0, 9.81])
        assert _same(rotation.from_gravity(*accel), tilt) < 1e-12


def test_level_heading_removes_the_scipy_zyx_yaw_and_keeps_the_tilt():
    for yaw, pitch, roll in np.random.default_rng(5).uniform(-3.1, 3.1, (100, 3)) * [
            1.0, 0.45, 1.0]:
        q = Rotation.from_euler('ZYX', [yaw, pitch, roll])
        turned = rotation.hamilton(rotation.level_heading(q.as_quat()), q.as_quat())
        assert _same(turned, Rotation.from_euler('ZYX', [0.0, pitch, roll])) < 1e-12


@pytest.mark.parametrize('noise', [0.0, 0.01, 1.0, 100.0])
def test_kabsch_equals_scipy_align_vectors(noise):
    """Rate pairs of a rotated frame, noisy up to no relation at all: scipy's rotation."""
    rng = np.random.default_rng(5)
    for seed in range(20):
        true = Rotation.random(random_state=seed)
        b = rng.normal(size=(500, 3)) * [1.0, 0.3, 0.05]
        a = true.apply(b) + noise * rng.normal(size=b.shape)
        r = rotation.kabsch(b.T @ a)
        assert (Rotation.from_matrix(r) * Rotation.align_vectors(a, b)[0].inv()).magnitude() \
            < 1e-9
        assert abs(np.linalg.det(r) - 1) < 1e-12


def test_kabsch_of_a_reflected_cloud_is_still_a_rotation():
    rng = np.random.default_rng(6)
    b = rng.normal(size=(300, 3))
    a = b * [1.0, 1.0, -1.0]  # a mirror image: the best rotation is not the best matrix
    r = rotation.kabsch(b.T @ a)
    ref, ref_rssd = Rotation.align_vectors(a, b)
    assert abs(np.linalg.det(r) - 1) < 1e-12
    assert abs(np.sqrt(np.sum((a - b @ r.T) ** 2)) - ref_rssd) < 1e-9 * ref_rssd


def test_yaw_turn_and_with_tilt_of_equal_scipys_euler_angles():
    """The yaw of one, the roll and pitch of the other, near a half turn of yaw too."""
    near = [Rotation.from_euler('ZYX', [np.pi - d * s, p, 0.4]) for d in (1e-3, 1e-9, 0.0)
            for s in (1, -1) for p in (0.3, -1.2)]
    cases = list(Rotation.random(500, random_state=4)) + near
    for a, b in zip(cases, cases[1:] + cases[:1]):
        turn = Rotation.from_quat(rotation.yaw_turn(tuple(a.as_quat())))
        assert _same(turn.as_quat(), Rotation.from_euler('z', a.as_euler('ZYX')[0])) < 1e-12
        both = rotation.with_tilt_of(tuple(a.as_quat()), tuple(b.as_quat()))
        want = Rotation.from_euler('ZYX', [a.as_euler('ZYX')[0], *b.as_euler('ZYX')[1:]])
        assert _same(both, want) < 1e-12
    assert rotation.yaw_turn(tuple(Rotation.from_euler('ZYX', [1.0, np.pi / 2, 0.0]).as_quat())
                             ) == (0.0, 0.0, 0.0, 1.0)  # the x axis vertical: no yaw


def test_relative_arrays_equal_scipys_inverse_composition():
    p, q = Rotation.random(300, random_state=6), Rotation.random(300, random_state=7)
    got = rotation.relative_arrays(p.as_quat(), q.as_quat())
    assert (Rotation.from_quat(got).inv() * (p.inv() * q)).magnitude().max() < 1e-12


@pytest.mark.parametrize('scale', [0.0, 1e-9, 1e-4, 1e-3, 0.1, 1.0, 3.1, np.pi - 1e-9, np.pi])
def test_log_arrays_equals_scipy_rotation_vectors_on_both_quaternion_signs(scale):
    rotvec = np.random.default_rng(7).normal(size=(400, 3))
    rotvec *= scale / np.maximum(np.linalg.norm(rotvec, axis=1, keepdims=True), 1e-300)
    rotvec[:200] *= np.random.default_rng(8).uniform(0.5, 1.0, (200, 1))
    quat = Rotation.from_rotvec(rotvec).as_quat()
    for q in (quat, -quat):  # the same rotations, w < 0 on one side
        np.testing.assert_allclose(rotation.log_arrays(q), Rotation.from_quat(q).as_rotvec(),
                                   rtol=0, atol=1e-14)
    assert rotation.log_arrays(quat.reshape(4, 100, 4)).shape == (4, 100, 3)


def test_log_arrays_takes_scipys_sign_at_exactly_a_half_turn():
    quat = np.array([[1.0, 0, 0, 0], [-1.0, 0, 0, 0], [0, -0.6, 0.8, 0], [0, 0, -1.0, -0.0],
                     [-0.6, 0.8, 0, 0]])
    np.testing.assert_allclose(rotation.log_arrays(quat), Rotation.from_quat(quat).as_rotvec(),
                               rtol=0, atol=1e-15)
