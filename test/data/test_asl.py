# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""ASL reading and ground-truth alignment, on real data and on broken files."""

from denoise_imu_ros.core.errors import DatasetError
from denoise_imu_ros.data.load import load_sequence
from helpers import break_line, T0, write_asl
import numpy as np
import pytest


def test_real_euroc_sequence_is_aligned_at_200_hz(euroc):
    seq = load_sequence(euroc / 'MH_01_easy')
    assert seq.stamp_ns.dtype == np.int64 and len(seq) > 30000
    assert seq.rate_hz == pytest.approx(200.0, rel=1e-3)
    assert seq.gt_valid.all()
    np.testing.assert_allclose(np.linalg.norm(seq.gt_quat, axis=1), 1.0, atol=1e-12)


def test_real_tumvi_mocap_holes_are_masked(data_dir):
    seq = load_sequence(data_dir / 'tumvi' / 'dataset-room3_512_16')
    assert 0.8 < seq.gt_valid.mean() < 0.99


def test_quaternions_are_read_as_wxyz_and_stored_xyzw(tmp_path):
    seq = load_sequence(write_asl(tmp_path / 's', yaw_rate=0.5))
    yaw = 0.5 * (seq.stamp_ns - T0) * 1e-9
    np.testing.assert_allclose(seq.gt_quat[:, 2], np.sin(yaw / 2), atol=1e-9)
    np.testing.assert_allclose(seq.gt_quat[:, 3], np.cos(yaw / 2), atol=1e-9)
    assert seq.stamp_ns[0] == T0  # nanoseconds survive parsing exactly


def test_a_csv_read_again_is_parsed_once_and_written_anew_is_read_anew(tmp_path, monkeypatch):
    from denoise_imu_ros.data import asl
    root = write_asl(tmp_path / 's', n_imu=400)
    first = asl.read_asl(root)
    first.imu[:] = 0.0  # the caller's own arrays: what is kept stays as read
    parsed = []
    real = asl._read_csv
    monkeypatch.setattr(asl, '_read_csv', lambda *args: parsed.append(args) or real(*args))
    assert asl.read_asl(root).imu[0, 5] == 9.81 and parsed == []
    csv = root / 'mav0' / 'imu0' / 'data.csv'
    csv.write_text(csv.read_text().replace(',9.81\n', ',9.8\n'))  # written anew: read anew
    assert asl.read_asl(root).imu[0, 5] == 9.8 and [a[0] for a in parsed] == [csv]


def test_overlap_crop_and_interpolation_to_imu_stamps(tmp_path):
    seq = load_sequence(write_asl(tmp_path / 's', gt_rate=120.0, gt_offset_s=0.5))
    assert seq.stamp_ns[0] >= T0 + 500_000_000
    yaw = 0.3 * (seq.stamp_ns - T0) * 1e-9
    np.testing.assert_allclose(seq.gt_quat[:, 2], np.sin(yaw / 2), atol=1e-9)


def test_ground_truth_hole_is_masked_and_only_the_hole(tmp_path):
    seq = load_sequence(write_asl(tmp_path / 's', n_imu=2000, gt_rate=120.0,
                                  gt_dir='mocap0', gt_hole=(3.0, 4.5)))
    rel = (seq.stamp_ns - T0) * 1e-9
    inside = (rel > 3.0) & (rel < 4.5)
    assert not seq.gt_valid[inside].any()
    assert seq.gt_valid[(rel < 2.99) | (rel > 4.51)].all()


@pytest.mark.parametrize('gt_rate', [20.0, 10.0])
def test_low_rate_ground_truth_on_its_own_clock_is_trusted_between_its_samples(
        tmp_path, gt_rate):
    # VIO poses at 10-20 Hz, 3.7 ms off the IMU clock: holes are judged by their own spacing
    seq = load_sequence(write_asl(tmp_path / 's', n_imu=2000, gt_rate=gt_rate,
                                  gt_offset_s=0.0037, gt_hole=(4.0, 6.0)))
    rel = (seq.stamp_ns - T0) * 1e-9
    assert seq.gt_valid[rel < 3.9].all() and seq.gt_valid[rel > 6.1].all()
    assert not seq.gt_valid[(rel > 4.2) & (rel < 5.8)].any()
    yaw = 0.3 * rel
    ok = seq.gt_valid
    np.testing.assert_allclose(seq.gt_quat[ok, 2], np.sin(yaw[ok] / 2), atol=1e-9)


def test_ten_hz_poses_give_the_aoe_of_the_200_hz_ground_truth(euroc):
    import dataclasses
    from denoise_imu_ros.core.metrics import score
    from denoise_imu_ros.data.asl import read_asl
    from denoise_imu_ros.data.timebase import onto_imu_stamps
    from scipy.spatial.transform import Rotation, RotationSpline
    rec = read_asl(euroc / 'V1_03_difficult')
    gyro = rec.imu[:, :3] - np.radians([-0.13, 1.21, 4.39])  # a fixed ADIS16448 bias
    full = onto_imu_stamps(rec)
    reference = score(full, gyro[np.searchsorted(rec.imu_stamp_ns, full.stamp_ns)])
    # 10 Hz poses on a clock 3.7 ms off the IMU's (sampled from the 200 Hz ground truth)
    rel = (rec.gt_stamp_ns - rec.gt_stamp_ns[0]) * 1e-9
    t = rec.gt_stamp_ns[5::20][:-1] + 3_700_000
    spline = RotationSpline(rel, Rotation.from_quat(rec.gt_quat))
    t_rel = (t - rec.gt_stamp_ns[0]) * 1e-9
    pos = np.stack([np.interp(t_rel, rel, rec.gt_pos[:, i]) for i in range(3)], axis=1)
    slow = onto_imu_stamps(dataclasses.replace(rec, gt_stamp_ns=t,
                                               gt_quat=spline(t_rel).as_quat(), gt_pos=pos))
    assert slow.gt_valid.all()
    result = score(slow, gyro[np.searchsorted(rec.imu_stamp_ns, slow.stamp_ns)])
    assert 1.0 < reference['aoe_deg'] < 10.0
    assert result['aoe_deg'] == pytest.approx(reference['aoe_deg'], rel=0.1)
    assert result['aoe_yaw_deg'] == pytest.approx(reference['aoe_yaw_deg'], rel=0.1)


def test_ground_truth_never_trusted_is_an_error(tmp_path):
    from denoise_imu_ros.data.asl import read_asl
    from denoise_imu_ros.data.timebase import onto_imu_stamps
    rec = read_asl(write_asl(tmp_path / 's', gt_rate=20.0, gt_offset_s=0.0037))
    with pytest.raises(DatasetError, match='ground truth is never trusted'):
        onto_imu_stamps(rec, max_gt_gap_s=0.01)


@pytest.mark.parametrize('damage, message', [
    (lambda r: None, None),
    (lambda r: (r / 'mav0' / 'imu0' / 'data.csv').unlink(), 'imu0/data.csv: file not found'),
    (lambda r: break_line(r / 'mav0' / 'imu0' / 'data.csv', 5, f'{T0 + 20_000_000},1,2'),
     'data.csv:6: expected 7 columns, found 3'),
    (lambda r: break_line(r / 'mav0' / 'imu0' / 'data.csv', 5, f'{T0},a,b,c,d,e,f'),
     'data.csv:6: unparsable row'),
    (lambda r: break_line(r / 'mav0' / 'imu0' / 'data.csv', 5, f'{T0 + 1},0,0,0,0,0,9.8'),
     'non-monotonic IMU stamp at sample 4'),
    (lambda r: break_line(r / 'mav0' / 'imu0' / 'data.csv', 5, f'{T0 + 15_000_000},0,0,0,0,0,1'),
     'duplicate IMU stamp at sample 4'),
    (lambda r: break_line(r / 'mav0' / 'imu0' / 'data.csv', 5, f'{T0 + 20_000_000},nan,0,0,0,0,1'),
     'non-finite IMU values in sample 4'),
    (lambda r: break_line(r / 'mav0' / 'state_groundtruth_estimate0' / 'data.csv', 3,
                          f'{T0 + 10_000_000},0,0,0,nan,0,0,0'), 'non-finite ground truth'),
    (lambda r: break_line(r / 'mav0' / 'imu0' / 'data.csv', 5, '1' * 20 + ',0,0,0,0,0,9.8'),
     'data.csv:6: stamp 11111111111111111111 does not fit in 64-bit nanoseconds'),
    (lambda r: (r / 'mav0' / 'imu0' / 'data.csv').write_text(  # a BOM: read as text
        '\ufeff' + (r / 'mav0' / 'imu0' / 'data.csv').read_text()), None),
])
def test_broken_asl_files_raise_a_clear_error_naming_the_file(tmp_path, damage, message):
    root = write_asl(tmp_path / 'seq')
    damage(root)
    if message is None:
        assert len(load_sequence(root)) > 100
        return
    with pytest.raises(DatasetError, match=message):
        load_sequence(root)


def test_missing_folders_and_ground_truth_are_reported(tmp_path):
    with pytest.raises(DatasetError, match='no such sequence folder'):
        load_sequence(tmp_path / 'absent')
    (tmp_path / 'empty').mkdir()
    with pytest.raises(DatasetError, match=r'empty: not an ASL sequence folder'):
        load_sequence(tmp_path / 'empty')
    root = write_asl(tmp_path / 'nogt')
    for f in (root / 'mav0' / 'state_groundtruth_estimate0').iterdir():
        f.unlink()
    (root / 'mav0' / 'state_groundtruth_estimate0').rmdir()
    with pytest.raises(DatasetError, match='no ground truth'):
        load_sequence(root)


def test_no_time_overlap_and_too_short_sequences_are_refused(tmp_path):
    with pytest.raises(DatasetError, match='do not overlap'):
        load_sequence(write_asl(tmp_path / 'a', gt_offset_s=100.0))
    with pytest.raises(DatasetError, match='need at least 511'):
        load_sequence(write_asl(tmp_path / 'b', n_imu=400), min_samples=511)


def test_the_mav0_folder_itself_is_pointed_to_its_parent(tmp_path):
    from denoise_imu_ros.data.asl import read_asl
    from helpers import write_asl
    write_asl(tmp_path / 'seq')
    with pytest.raises(DatasetError, match=r'no mav0/ inside; give its parent, .*seq\)$'):
        read_asl(tmp_path / 'seq' / 'mav0')
