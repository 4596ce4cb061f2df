# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""check-data: rates, holes and the label-noise profile that picks increment lengths."""

import dataclasses
import json
import math
import re

from denoise_imu_ros.cli import main
from denoise_imu_ros.core.errors import DatasetError
from denoise_imu_ros.data.asl import read_asl
from denoise_imu_ros.data.check import check, ESTIMATES, label_noise, markdown
from denoise_imu_ros.data.check import paper_increments, supervision
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.data.pose_alignment import estimate_pose_alignment, read_and_align
from denoise_imu_ros.data.timebase import crop, onto_imu_stamps
from helpers import ROOT, write_asl
import numpy as np
import pytest
from scipy.spatial.transform import Rotation


def test_clean_and_jittery_ground_truth_are_told_apart(tmp_path):
    rec = read_asl(write_asl(tmp_path / 's', n_imu=6000, gt_rate=120.0, gt_dir='mocap0',
                             gt_hole=(10.0, 11.0), gyro_bias=0.01))
    clean = check(rec)
    assert abs(clean['gyro_bias_deg_s'][2] - np.degrees(0.01)) < 1e-3
    assert clean['noise_dominated_increments'] == []
    assert clean['pose_holes'] == 1 and 0.9 < clean['pose_longest_hole_s'] < 1.1
    assert abs(clean['pose_rate_hz'] - 120.0) < 0.5 and abs(clean['imu_rate_hz'] - 200) < 0.1
    assert clean['usable'] == 'no'  # a constant yaw rate: no x or y rotation, no clock
    # 3 mrad of white jitter on every pose: short increments measure it, not the gyro
    rng = np.random.default_rng(0)
    jitter = Rotation.from_rotvec(rng.normal(0, 3e-3, (len(rec.gt_quat), 3)))
    noisy_rec = dataclasses.replace(
        rec, gt_quat=(Rotation.from_quat(rec.gt_quat) * jitter).as_quat())
    noisy = label_noise(onto_imu_stamps(noisy_rec))
    assert {16, 32} <= set(noisy['noise_dominated_increments'])
    assert 64 not in noisy['noise_dominated_increments']
    assert check(noisy_rec)['label_noise'].startswith(
        'increments of 16 and 32 samples are dominated by ground-truth noise; from 64')


def test_the_poses_noise_is_split_into_their_heading_and_their_tilt(tmp_path):
    rec = read_asl(write_asl(tmp_path / 's', n_imu=6000, gt_rate=120.0, gt_dir='mocap0'))
    # the IMU mounted rolled over: its z is horizontal, so the split needs the world frame
    mount = Rotation.from_rotvec([math.pi / 2, 0.0, 0.0])
    rec = dataclasses.replace(
        rec, gt_quat=(Rotation.from_quat(rec.gt_quat) * mount).as_quat(),
        imu=np.hstack([mount.inv().apply(rec.imu[:, :3]), mount.inv().apply(rec.imu[:, 3:])]))
    rng = np.random.default_rng(1)
    split = {}
    for axis in (0, 2):  # jitter about the world's x (tilt), then its vertical (heading)
        about = np.zeros((len(rec.gt_quat), 3))
        about[:, axis] = rng.normal(0, 3e-3, len(rec.gt_quat))
        jittered = dataclasses.replace(rec, gt_quat=(
            Rotation.from_rotvec(about) * Rotation.from_quat(rec.gt_quat)).as_quat())
        profile = label_noise(onto_imu_stamps(jittered))['increments'][64]
        split[axis] = profile['heading_mrad'], profile['tilt_mrad']
    assert split[0][1] > 5 * split[0][0]  # tilt noise is tilt
    assert split[2][0] > 5 * split[2][1]  # heading noise is heading


def test_poses_whose_increments_disagree_with_their_own_attitude_cannot_supervise(tmp_path):
    rec = read_asl(write_asl(tmp_path / 's', n_imu=12000, gt_rate=120.0, gt_dir='mocap0',
                             gyro_bias=0.01))
    biased = supervision(onto_imu_stamps(rec), (16, 32, 256))
    assert biased['helps'] and biased['aoe_plain_deg'] > 10 and biased['summary'].startswith(
        "a constant gyro bias fitted on the poses' own")
    for fit in biased['fits'].values():
        np.testing.assert_allclose(fit['bias_deg_s'], [0, 0, np.degrees(0.01)], atol=1e-4)
        assert fit['aoe_deg'] < 0.01
    holes = onto_imu_stamps(rec)
    holes = dataclasses.replace(holes, gt_valid=np.arange(len(holes)) % 10 > 0)
    none = supervision(holes, (16, 32))
    assert not none['helps'] and none['fits'] == {} and none['summary'] == (
        'no increment of 16, 32 samples has trusted poses at every stamp: nothing supervises '
        'a correction')
    # an exact gyro, and mocap whose yaw creeps at 1 deg/s and jumps back in a 0.3 s hole
    # every 5 s (a re-acquired marker): every trusted increment says "bias", none is one
    rec = read_asl(write_asl(tmp_path / 'e', n_imu=12000, gt_rate=120.0, gt_dir='mocap0'))
    t = (rec.gt_stamp_ns - rec.gt_stamp_ns[0]) * 1e-9
    keep = np.abs(t - 5.0 * np.round(t / 5.0)) > 0.15
    creep = Rotation.from_rotvec(np.outer(np.radians(1.0) * (t % 5.0), [0, 0, 1]))
    jumpy = dataclasses.replace(rec, gt_stamp_ns=rec.gt_stamp_ns[keep], gt_pos=rec.gt_pos[keep],
                                gt_quat=(creep * Rotation.from_quat(rec.gt_quat)).as_quat()[keep])
    report = supervision(onto_imu_stamps(jumpy), (16, 32, 256))
    assert not report['helps']
    assert all(f['aoe_deg'] > 5 * report['aoe_plain_deg'] for f in report['fits'].values())
    assert report['summary'] in check(jumpy)['reasons']


def test_check_data_on_real_recordings(data_dir, capsys):
    assert main(['check-data', '--input', str(data_dir / 'tumvi' / 'dataset-room1_512_16'),
                 '--json']) == 0
    tumvi = json.loads(capsys.readouterr().out.splitlines()[-1])
    assert set(ESTIMATES) <= set(tumvi)  # what a too-short recording reports as null
    assert {16, 32} <= set(map(int, tumvi['noise_dominated_increments']))
    assert abs(tumvi['time_offset_s']) < 1e-3 and tumvi['usable'] == 'yes'
    assert tumvi['imu_from_pose_rotation_deg'] < 0.2
    # room1's own mocap supervises a bias over 256 samples, room3's at no length tried
    assert tumvi['supervision']['helps'] and tumvi['supervision']['fits']['256']['aoe_deg'] < 1
    room3 = check(read_asl(data_dir / 'tumvi' / 'dataset-room3_512_16'))
    assert not room3['supervision']['helps'] and room3['reasons'] == [
        room3['supervision']['summary']]
    euroc = check(read_asl(data_dir / 'euroc' / 'V1_01_easy'))  # 20 Hz corrected poses
    assert 19.5 < euroc['pose_rate_hz'] < 20.5
    assert not {16, 32} & set(euroc['noise_dominated_increments'])
    assert euroc['supervision']['fits'][16]['aoe_deg'] < 1.0  # from 114 deg of raw gyro
    assert abs(euroc['time_offset_s']) < 1e-3 and euroc['imu_from_pose_rotation_deg'] < 0.2
    assert max(map(abs, euroc['interpolation_scale_error_percent'])) < 0.2
    assert euroc['too_sparse'] is None and euroc['rate_windows_left_out'] < 0.01
    # V2_03's poses lag by +2 to -4 ms along the recording: reported, not "fixed"
    drift = check(read_asl(data_dir / 'euroc' / 'V2_03_difficult'))
    assert drift['usable'] == 'yes' and abs(drift['time_offset_s']) < 2 * (
        drift['time_offset_std_s'])
    assert drift['reasons'][0].startswith('the clock offset is not constant: +2.')


def test_the_papers_increments_follow_the_rate_in_seconds():
    assert [paper_increments(r) for r in (100, 199.4, 200, 400, 1000)] == [
        (8, 16), (16, 32), (16, 32), (32, 64), (64, 128)]


def test_label_noise_and_supervision_are_judged_on_the_poses_as_training_aligns_them(euroc):
    rec = crop(read_asl(euroc / 'MH_01_easy'), 0.0, 100.0)
    # a camera's 10 Hz poses: its frame 90 deg from the IMU's, its clock 90 ms late
    keep = slice(None, None, 20)
    camera = Rotation.from_rotvec([0.0, 0.0, 90.0], degrees=True)
    moved = dataclasses.replace(
        rec, gt_stamp_ns=rec.gt_stamp_ns[keep] - 90_000_000,
        gt_quat=(Rotation.from_quat(rec.gt_quat[keep]) * camera).as_quat(),
        gt_pos=rec.gt_pos[keep])
    same = dataclasses.replace(rec, gt_stamp_ns=rec.gt_stamp_ns[keep],
                               gt_quat=rec.gt_quat[keep], gt_pos=rec.gt_pos[keep])
    judged, plain = check(moved), check(same)
    assert judged['judged_after_alignment'] and not plain['judged_after_alignment']
    assert judged['usable'] == 'after alignment'
    # the camera's poses judged as the IMU's own 10 Hz poses are: the frame and clock
    # would otherwise make every increment "noise" (the VIO: up to 512 samples)
    assert judged['noise_dominated_increments'] == plain['noise_dominated_increments']
    for j in (64, 128, 256):
        assert judged['increments'][j]['noise_rate_deg_s'] == pytest.approx(
            plain['increments'][j]['noise_rate_deg_s'], rel=0.1)
    assert judged['supervision']['helps']


def test_unusable_recordings_get_a_one_line_verdict_and_exit_code_1(tmp_path, capsys, euroc):
    # yaw only: nothing about x and y
    flat = write_asl(tmp_path / 'flat', n_imu=8000)
    assert main(['check-data', '--input', str(flat)]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert 'not usable for training: no rotation about the IMU x axis' in err
    # too short
    rec = crop(read_asl(euroc / 'MH_01_easy'), 0.0, 60.0)
    short = dataclasses.replace(rec, imu_stamp_ns=rec.imu_stamp_ns[:4000],
                                imu=rec.imu[:4000])
    assert check(short)['reasons'][0].startswith('too short: 18.9 s of IMU with poses')
    # shorter than the receptive field: nothing is estimated, the JSON says so with nulls
    from denoise_imu_ros.data.bags import write_bag
    write_bag(crop(rec, 0.0, 2.0), tmp_path / 'tiny')  # 400 IMU samples
    assert main(['check-data', '--input', str(tmp_path / 'tiny'), '--json']) == 1
    out, err = capsys.readouterr()
    assert json.loads(out.splitlines()[-1])['time_offset_s'] is None
    assert len(err.strip().splitlines()) == 1
    assert "fewer than the network's receptive field (511 samples)" in err
    # poses 2 s late: beyond the 0.5 s search, found where the rate norms match best
    late = dataclasses.replace(rec, gt_stamp_ns=rec.gt_stamp_ns - 2_000_000_000)
    report = check(late)
    assert abs(report['time_offset_s'] - 2.0) < 1e-3 and not report['time_offset_at_search_limit']
    # another recording's poses: not followed at any offset, nor read another way
    other = dataclasses.replace(rec, gt_quat=read_asl(euroc / 'MH_02_easy').gt_quat[
        :len(rec.gt_quat)])
    with pytest.raises(DatasetError, match='no pose rate to compare with the gyro'):
        jumping = crop(rec, 0.0, 40.0)  # poses that jump everywhere: nothing to compare, said
        check(dataclasses.replace(jumping, gt_quat=Rotation.random(
            len(jumping.gt_quat), random_state=4).as_quat()))
    assert 'do not follow the gyro at any clock offset searched (within +-0.5 s' in ' '.join(
        check(other)['reasons'])
    # and align auto does not apply such an estimate (eval --align auto, training)
    write_bag(crop(other, 0.0, 40.0), tmp_path / 'other')
    with pytest.raises(DatasetError, match='other: align auto: the poses do not follow'):
        load_sequence(tmp_path / 'other', align_poses='auto')
    with pytest.raises(DatasetError, match=r'other: .* do not follow .* \(nor read inverted'):
        load_sequence(tmp_path / 'other', align_poses='check')  # eval's default: not scored
    # ground truth written x, y, z, w and read as w, x, y, z (a fixed rotation of each pose
    # on both sides): refused by eval's default, not scored as 17 deg
    write_bag(crop(dataclasses.replace(rec, gt_quat=np.roll(rec.gt_quat, -1, axis=1)), 0.0, 40.0),
              tmp_path / 'order')
    with pytest.raises(DatasetError, match=r'order: poses .* in a frame 155\.\d\d deg from the '
                                           "IMU's: figures against them as they are would be"):
        load_sequence(tmp_path / 'order', align_poses='check')
    # no overlap at all: scored as they are, refused in one line that says the spans
    away = write_asl(tmp_path / 'away', n_imu=2000, gt_offset_s=20.0)
    with pytest.raises(DatasetError, match=r'do not overlap in time \(IMU .* to .* s, poses .* '
                                           'to .* s; align auto finds poses on another clock'):
        load_sequence(away)


def test_poses_stamped_on_a_clock_the_imus_overlaps_nowhere_are_found(euroc, tmp_path):
    rec = crop(read_asl(euroc / 'MH_01_easy'), 0.0, 110.0)
    part = dataclasses.replace(rec, imu_stamp_ns=rec.imu_stamp_ns[:12000], imu=rec.imu[:12000])
    camera = _camera_poses(part, slice(None, None, 20))  # 10 Hz, 90 ms late, 90 deg off
    start = int(camera.gt_stamp_ns[0])
    # stamped in time since their start (a tool's own clock): judged where they lie
    since = dataclasses.replace(camera, gt_stamp_ns=camera.gt_stamp_ns - start)
    base, report = check(camera), check(since)
    assert abs(report['time_offset_s'] - start * 1e-9 - base['time_offset_s']) < 1e-3
    turn = Rotation.from_quat(report['imu_from_pose_rotation_xyzw']).inv() * Rotation.from_quat(
        base['imu_from_pose_rotation_xyzw'])
    assert math.degrees(turn.magnitude()) < 0.2 and report['usable'] == base['usable']
    assert report['duration_s'] == pytest.approx(base['duration_s'], abs=0.1)  # the 90 ms
    assert report['label_noise'] == base['label_noise']
    np.testing.assert_allclose(report['interpolation_scale_error_percent'],
                               base['interpolation_scale_error_percent'], atol=0.02)
    assert re.match(r'poses \+\d{10}\.\d{4} s off the IMU clock', report['reasons'][0])
    # a part of it, mostly still (the gyro's norm then its bias alone): found as well
    span = (since.gt_stamp_ns >= 20e9) & (since.gt_stamp_ns < 50e9)
    still = dataclasses.replace(since, gt_stamp_ns=since.gt_stamp_ns[span] - int(20e9),
                                gt_quat=since.gt_quat[span], gt_pos=since.gt_pos[span])
    found = read_and_align(still)[1]['time_offset_s'] - (start * 1e-9 + 20)
    assert abs(found - base['time_offset_s']) < 0.02  # 10 Hz: 7.5 ms here
    # poses from 45 s on (in flight), an IMU hole where they lie, not where placing them at
    # the IMU's start puts them: said, and not usable
    t = (rec.imu_stamp_ns - rec.imu_stamp_ns[0]) * 1e-9
    keep = (t < 90) | ((t > 90.2) & (t < 100))
    span = (since.gt_stamp_ns >= 45e9) & (since.gt_stamp_ns < 95e9)
    late = dataclasses.replace(rec, imu_stamp_ns=rec.imu_stamp_ns[keep], imu=rec.imu[keep],
                               gt_stamp_ns=since.gt_stamp_ns[span] - int(45e9),
                               gt_quat=since.gt_quat[span], gt_pos=since.gt_pos[span])
    holed = check(late)
    assert holed['imu_holes'] == 1 and holed['usable'] == 'no'
    # as a trajectory file: training and eval (align auto) read the poses on the IMU's clock
    from denoise_imu_ros.data.bags import write_bag
    from denoise_imu_ros.data.trajectory import write_tum
    write_bag(part, tmp_path / 'part')
    write_tum(tmp_path / 'part.txt', since.gt_stamp_ns, since.gt_pos, since.gt_quat)
    seq = load_sequence(tmp_path / 'part', poses=tmp_path, align_poses='auto')
    truth = load_sequence(tmp_path / 'part')
    assert abs(seq.pose_alignment['time_offset_s'] - report['time_offset_s']) < 1e-3
    ours, real = (Rotation.from_quat(one.gt_quat[np.isin(one.stamp_ns, seq.stamp_ns)])
                  for one in (seq, truth))
    assert np.degrees((ours[:-1].inv() * ours[1:] * (real[:-1].inv() * real[1:]).inv())
                      .magnitude()).max() < 0.5
    with pytest.raises(DatasetError, match=r'poses \+\d+\.\d{4} s off the IMU clock .* give '
                                           '--align auto'):  # eval's default: not scored
        load_sequence(tmp_path / 'part', poses=tmp_path, align_poses='check')
    # another recording's poses so stamped: one line, not an alignment
    quat = read_asl(euroc / 'MH_02_easy').gt_quat[:len(part.gt_quat)]
    other = dataclasses.replace(part, gt_stamp_ns=part.gt_stamp_ns[:len(quat)] - start,
                                gt_quat=quat, gt_pos=part.gt_pos[:len(quat)])
    with pytest.raises(DatasetError, match=r"on another clock than the IMU's \(IMU .*\) and do "
                                           "not follow .* another recording's trajectory"):
        check(other)


def test_stamps_in_microseconds_and_a_bad_search_range_are_one_line_errors(tmp_path, capsys):
    """Stamps in microseconds, and a --max-offset below the search's resolution: one line."""
    root = write_asl(tmp_path / 's', n_imu=2000)
    csv = root / 'mav0' / 'imu0' / 'data.csv'
    lines = csv.read_text().splitlines()
    micro = [lines[0]] + [f'{int(x.split(",")[0]) // 1000},{x.split(",", 1)[1]}'
                          for x in lines[1:]]
    csv.write_text('\n'.join(micro) + '\n')
    for cmd in (['check-data', '--input', str(root)],
                ['init-recipe', '--data', str(tmp_path), '--sequences', 's',
                 '--out', str(tmp_path / 'r.yaml')]):
        assert main(cmd) == 1
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and 'stamps in microseconds or milliseconds?' in err
    for bad in ('-1', '0', 'nan', '0.002'):  # 2 ms: below the search's resolution
        assert main(['check-data', '--input', str(root), '--max-offset', bad]) == 1
        assert '--max-offset' in capsys.readouterr().err


@pytest.mark.parametrize('column, factor, cause', [
    (slice(4, 7), 1 / 9.81, 'accelerometer in g?'),
    (slice(1, 4), 180 / math.pi, 'gyro in deg/s?')])
def test_wrong_units_are_named_by_check_data_correct_eval_and_train(
        euroc, tmp_path, capsys, model_file, column, factor, cause):
    """A 45 s crop of MH_01 with one sensor in other units."""
    import yaml
    from denoise_imu_ros.data.asl import read_asl
    from denoise_imu_ros.data.bags import write_bag
    rec = crop(read_asl(euroc / 'MH_01_easy'), 0.0, 45.0)
    imu = rec.imu.copy()
    imu[:, column.start - 1:column.stop - 1] *= factor
    write_bag(dataclasses.replace(rec, imu=imu), tmp_path / 'bag')
    assert main(['check-data', '--input', str(tmp_path / 'bag')]) == 1
    err = capsys.readouterr().err.strip()
    tail = cause + (' (rad/s expected)' if 'gyro' in cause else '')
    assert len(err.splitlines()) == 1 and err.endswith(tail)
    for cmd in (['correct', '--model', 'euroc', '--input', str(tmp_path / 'bag'), '--out',
                 str(tmp_path / 'c.csv'), '--engine', 'streaming'],
                ['eval', '--model', 'euroc', '--data', str(tmp_path), '--sequences', 'bag',
                 '--out', str(tmp_path / 'ev'), '--no-plots']):
        assert main(cmd) == 1
        assert cause in capsys.readouterr().err
    # train has no model to compare the gyro with: the poses' own rate says deg/s
    recipe = yaml.safe_load((ROOT / 'config' / 'train_euroc.yaml').read_text())
    recipe.update(data=str(tmp_path), sequences=['bag'], window=1024, steps=2, val_every=1,
                  restart_period=2, swa_start=1, workers=1)
    (tmp_path / 'r.yaml').write_text(yaml.safe_dump(recipe))
    assert main(['train', '--recipe', str(tmp_path / 'r.yaml'), '--out',
                 str(tmp_path / 'm.safetensors')]) == 1
    assert cause in capsys.readouterr().err and not (tmp_path / 'm.safetensors').exists()


def test_an_imu_hole_is_named_offline_as_the_node_treats_it(euroc, tmp_path, capsys):
    """One 5 s hole in 45 s of MH_01."""
    from denoise_imu_ros.data.asl import read_asl
    from denoise_imu_ros.data.bags import write_bag
    rec = crop(read_asl(euroc / 'MH_01_easy'), 0.0, 45.0)
    t = (rec.imu_stamp_ns - rec.imu_stamp_ns[0]) * 1e-9
    keep = (t < 20) | (t >= 25)
    write_bag(dataclasses.replace(rec, imu_stamp_ns=rec.imu_stamp_ns[keep], imu=rec.imu[keep]),
              tmp_path / 'bag')
    assert main(['check-data', '--input', str(tmp_path / 'bag')]) == 1
    assert '1 IMU holes longer than 3 periods (longest 5.01 s)' in capsys.readouterr().err
    for cmd in (['correct', '--model', 'euroc', '--input', str(tmp_path / 'bag'), '--out',
                 str(tmp_path / 'c.csv'), '--engine', 'streaming'],
                ['eval', '--model', 'euroc', '--data', str(tmp_path), '--sequences', 'bag',
                 '--out', str(tmp_path / 'ev'), '--no-plots']):
        assert main(cmd) == 1
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1
        assert re.search(r'IMU hole of 5.01 s after sample \d+ \(1 longer than 3 periods', err)


def test_poses_too_sparse_to_give_a_rate_are_a_clear_error(tmp_path):
    """Poses 3.3 s apart over 6.7 s: no window of their rate (two periods) fits inside."""
    from helpers import write_asl
    rec = read_asl(write_asl(tmp_path / 's', n_imu=1600, gt_rate=0.3))
    with pytest.raises(DatasetError, match='over which their rate is compared'):
        estimate_pose_alignment(rec)


def test_a_saturated_gyro_is_named_not_taken_for_a_frame_rotation(euroc, tmp_path):
    rec = read_asl(euroc / 'MH_04_difficult')
    limit = np.percentile(np.abs(rec.imu[:, 2]), 95)  # the fastest 5 % of yaw clipped
    imu = rec.imu.copy()
    imu[:, 2] = np.clip(imu[:, 2], -limit, limit)
    report = check(dataclasses.replace(rec, imu=imu))
    assert report['usable'] == 'no' and report['gyro_clipped']['axis'] == 'z'
    assert report['reasons'][0].startswith('gyro saturated: ')
    assert f'pinned at +-{math.degrees(limit):.4g} deg/s on its z axis' in report['reasons'][0]
    plain = check(rec)
    assert plain['gyro_clipped'] is None and plain['accel_clipped'] is None


def _camera_poses(rec, keep, late_ms=90):
    """``rec``'s poses as a camera 90 deg from the IMU writes them, late, at ``keep``."""
    camera = Rotation.from_rotvec([0.0, 0.0, 90.0], degrees=True)
    return dataclasses.replace(
        rec, gt_stamp_ns=rec.gt_stamp_ns[keep] - late_ms * 1_000_000,
        gt_quat=(Rotation.from_quat(rec.gt_quat[keep]) * camera).as_quat(),
        gt_pos=rec.gt_pos[keep])


def test_an_initialising_vios_first_seconds_do_not_move_the_alignment(euroc):
    rec = read_asl(euroc / 'MH_01_easy')
    clean = _camera_poses(rec, slice(None, None, 20))
    # its first 5 s wrong by 8 deg per axis and pose, at random (a VIO initialising)
    t = (clean.gt_stamp_ns - clean.gt_stamp_ns[0]) * 1e-9
    wrong = Rotation.from_rotvec(np.random.default_rng(3).normal(0, np.radians(8), (
        int(np.count_nonzero(t < 5.0)), 3)))
    quat = clean.gt_quat.copy()
    quat[t < 5.0] = (wrong * Rotation.from_quat(quat[t < 5.0])).as_quat()
    start = dataclasses.replace(clean, gt_quat=quat)
    base, found = estimate_pose_alignment(clean), estimate_pose_alignment(start)
    assert abs(found['time_offset_s'] - base['time_offset_s']) < 1e-3
    turn = Rotation.from_quat(found['imu_from_pose_rotation_xyzw']) * Rotation.from_quat(
        base['imu_from_pose_rotation_xyzw']).inv()
    assert math.degrees(turn.magnitude()) < 0.2
    assert found['rate_residual_rms_deg_s'] < 1.5 * base['rate_residual_rms_deg_s']
    # those seconds are 3.8 % of the recording: left out, and said
    assert 0.02 < found['rate_windows_left_out'] < 0.06
    report = check(start)
    assert report['usable'] == 'after alignment' and report['judged_after_alignment']
    assert report['pose_jumps'][0]['start_s'] < 1.0  # masked for training
    assert re.search(r'left out of the alignment: \d\.\d % of its rate windows',
                     markdown(report))


def test_keyframes_a_few_times_a_second_are_too_sparse_for_a_drone(euroc):
    rec = crop(read_asl(euroc / 'MH_01_easy'), 0.0, 100.0)
    # a SLAM's keyframe trajectory: a pose every 0.2-1.0 s
    t = (rec.gt_stamp_ns - rec.gt_stamp_ns[0]) * 1e-9
    gaps = np.random.default_rng(4).uniform(0.2, 1.0, 1000)
    wanted = np.cumsum(gaps)[np.cumsum(gaps) < t[-1]]
    keyframes = _camera_poses(rec, np.searchsorted(t, wanted))
    dense = _camera_poses(rec, slice(None, None, 20))
    sparse, full = check(keyframes), check(dense)
    assert abs(sparse['time_offset_s'] - 0.090) < 0.02  # keyframes place it less well
    # between them the interpolated attitude misses the drone's faster turns, which a
    # model would learn as the gyro's scale from increments of fixed length: usable, with
    # increments between the pose stamps, and said
    assert max(map(abs, full['interpolation_scale_error_percent'])) < 0.5
    assert full['too_sparse'] is None and full['usable'] == 'after alignment'
    assert min(sparse['interpolation_scale_error_percent']) < -5.0
    assert sparse['usable'] == 'after alignment' and sparse['too_sparse'] in sparse['reasons']
    assert sparse['too_sparse'].startswith('poses too sparse for the motion (1.')
    assert 'increments_between_poses' in sparse['too_sparse']
    # and so its label noise is judged between the pose stamps: no two poses 16 samples
    # apart, and what is compared is the poses' own noise, not interpolation's
    assert 'each between pose stamps' in markdown(sparse)
    assert 16 not in sparse['increments'] and 16 in full['increments']
    assert sparse['shortest_clean_increment'] <= 256
    # what the poses can see turn is the gyro over their longer windows, less than at 10 Hz
    assert all(s < f for s, f in zip(sparse['excitation_rms_deg_s'],
                                     full['excitation_rms_deg_s']))


@pytest.mark.parametrize('way', ['inverted', 'with w first'])
def test_poses_written_inverted_or_w_first_are_read_so_by_every_command(euroc, tmp_path, way):
    from denoise_imu_ros.core.errors import DataWarning
    from denoise_imu_ros.data.trajectory import write_tum
    from helpers import crop_asl
    euroc = crop_asl(euroc / 'MH_01_easy', tmp_path / 'euroc' / 'MH_01_easy', 100).parent
    rec = read_asl(euroc / 'MH_01_easy')  # its first 100 s: the still start, then flight
    camera = _camera_poses(rec, slice(None, None, 20))  # a camera's 10 Hz poses, 90 ms late
    rot = Rotation.from_quat(camera.gt_quat)
    if way == 'inverted':  # world-in-camera poses, as some tools write them
        quat, pos = rot.inv().as_quat(), -rot.inv().apply(camera.gt_pos)
    else:  # qw qx qy qz in the columns of qx qy qz qw
        quat, pos = rot.as_quat()[:, [3, 0, 1, 2]], camera.gt_pos
    written = dataclasses.replace(camera, gt_quat=quat, gt_pos=pos)
    base, report = check(camera), check(written)
    assert base['read_as'] is None and report['read_as'].startswith(way)
    assert abs(report['time_offset_s'] - base['time_offset_s']) < 1e-3
    assert abs(report['imu_from_pose_rotation_deg'] - base['imu_from_pose_rotation_deg']) < 0.2
    assert report['usable'] == 'after alignment' and any(
        f'only read {way}' in reason for reason in report['reasons'])
    # training and eval read the file so too, and say it
    write_tum(tmp_path / 'poses' / 'MH_01_easy.txt', written.gt_stamp_ns, pos, quat)
    with pytest.warns(DataWarning, match=f'follow the gyro only read {way}'):
        seq = load_sequence(euroc / 'MH_01_easy', poses=tmp_path / 'poses', align_poses='auto')
    truth = load_sequence(euroc / 'MH_01_easy')
    common = np.intersect1d(seq.stamp_ns, truth.stamp_ns)[::50]
    ours = Rotation.from_quat(seq.gt_quat[np.searchsorted(seq.stamp_ns, common)])
    real = Rotation.from_quat(truth.gt_quat[np.searchsorted(truth.stamp_ns, common)])
    relative = (ours[:-1].inv() * ours[1:]) * (real[:-1].inv() * real[1:]).inv()
    assert np.degrees(relative.magnitude()).max() < 0.5


def test_inverted_poses_on_the_imu_clock_and_frame_are_judged_and_trained_as_read(
        euroc, tmp_path):
    from denoise_imu_ros.data.trajectory import write_tum
    from denoise_imu_ros.learn.recipe import init_recipe
    from helpers import crop_asl
    euroc = crop_asl(euroc / 'MH_01_easy', tmp_path / 'euroc' / 'MH_01_easy', 100.0).parent
    rec = read_asl(euroc / 'MH_01_easy')
    rot = Rotation.from_quat(rec.gt_quat)
    quat, pos = rot.inv().as_quat(), -rot.inv().apply(rec.gt_pos)
    right, report = check(rec), check(dataclasses.replace(rec, gt_quat=quat, gt_pos=pos))
    # nothing to align once read inverted: judged on the poses as read, not as written
    assert report['read_as'].startswith('inverted') and not report['judged_after_alignment']
    assert report['usable'] == 'yes' and report['label_noise'] == right['label_noise']
    assert report['supervision']['aoe_plain_deg'] == pytest.approx(
        right['supervision']['aoe_plain_deg'], abs=0.01)
    # and the recipe aligns them, the only way training reads them so
    write_tum(tmp_path / 'MH_01_easy.txt', rec.gt_stamp_ns, pos, quat)
    recipe, said = init_recipe(euroc, ['MH_01_easy'], poses=tmp_path)
    assert recipe['align'] == 'auto'
    assert 'align auto: MH_01_easy read inverted (world-in-camera poses' in ' '.join(said)
