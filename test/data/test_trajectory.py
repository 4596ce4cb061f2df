# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""TUM trajectory files: read as evo reads them, rows tools get wrong dropped and counted."""

from pathlib import Path
import re
import warnings

from denoise_imu_ros.cli import main
from denoise_imu_ros.core.errors import DatasetError, DataWarning
from denoise_imu_ros.data.load import load_recording, load_sequence
from denoise_imu_ros.data.trajectory import read_tum, trajectory_file, write_tum
from helpers import crop_asl, T0, write_asl
import numpy as np
import pytest

POSE = '0.1 0.2 0.3 0 0 0 1'


def _heads(euroc: Path, names: list[str], folder: Path, seconds: float = 80.0) -> Path:
    """Return a folder of the first ``seconds`` of these EuRoC recordings."""
    for name in names:
        crop_asl(euroc / name, folder / name, seconds)
    return folder


def _write(path: Path, rows: list[str]) -> Path:
    path.write_text('\n'.join(rows) + '\n')
    return path


def test_a_real_vio_trajectory_reads_as_evo_reads_it(data_dir):
    from evo.tools import file_interface
    path = data_dir / 'euroc_vio' / 'vins_mono' / 'MH_01_easy.txt'
    ours = read_tum(path)
    theirs = file_interface.read_tum_trajectory_file(str(path))
    assert not ours.dropped
    np.testing.assert_allclose(ours.stamp_ns * 1e-9, theirs.timestamps, rtol=0, atol=1e-6)
    np.testing.assert_allclose(ours.pos, theirs.positions_xyz, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ours.quat, theirs.orientations_quat_wxyz[:, [1, 2, 3, 0]],
                               rtol=0, atol=1e-9)


def test_nanosecond_stamps_and_openvins_columns_read_as_the_same_poses(data_dir, tmp_path):
    path = data_dir / 'euroc_vio' / 'vins_mono' / 'MH_01_easy.txt'
    tum = read_tum(path)
    rows = np.loadtxt(path)
    # ORB-SLAM3's EuRoC files: the stamp in nanoseconds, fixed with six decimals
    nano = _write(tmp_path / 'nano.txt', [f'{t}.000000 ' + ' '.join(map(str, r))
                                          for t, r in zip(tum.stamp_ns, rows[:, 1:])])
    # OpenVINS: TUM's 8 columns, then the rotation's and the position's covariance
    ov = tmp_path / 'ov.txt'
    np.savetxt(ov, np.column_stack([rows, np.full((len(rows), 12), 1e-4)]), fmt='%.9f',
               header='timestamp(s) tx ty tz qx qy qz qw Pr11 Pr12 Pr13 Pr22 Pr23 Pr33 '
                      'Pt11 Pt12 Pt13 Pt22 Pt23 Pt33')
    # nanoseconds since the tool's start: told apart by the poses' spacing
    since = _write(tmp_path / 'since.txt', [f'{t - tum.stamp_ns[0]} ' + ' '.join(map(str, r))
                                            for t, r in zip(tum.stamp_ns, rows[:, 1:])])
    np.testing.assert_array_equal(read_tum(since).stamp_ns, tum.stamp_ns - tum.stamp_ns[0])
    assert 'stamps read as nanoseconds' in read_tum(since).read_as
    for other, said in ((read_tum(nano), 'stamps read as nanoseconds'),
                        (read_tum(ov), 'the first 8 of its 20 columns read (t x y z and a '
                                       'quaternion), the rest unused')):
        np.testing.assert_array_equal(other.stamp_ns, tum.stamp_ns)
        np.testing.assert_allclose(other.quat, tum.quat, rtol=0, atol=1e-8)
        np.testing.assert_allclose(other.pos, tum.pos, rtol=0, atol=1e-8)
        assert not other.dropped and other.summary() == (
            f'{other.path}: {len(tum.stamp_ns)} poses kept; {said}')
    assert tum.summary() == ''


def test_asl_state_csvs_read_as_evo_reads_them_and_their_header_says_w_first(data_dir, tmp_path):
    from evo.tools import file_interface
    # EuRoC's motion capture: ns stamps, commas, qw first as its header names it; its header
    # and first 15 s of poses
    full = data_dir / 'euroc' / 'MH_01_easy' / 'mav0' / 'state_groundtruth_estimate0' / 'data.csv'
    path = tmp_path / 'data.csv'
    path.write_text(''.join(full.read_text().splitlines(keepends=True)[:3001]))
    ours, theirs = read_tum(path), file_interface.read_euroc_csv_trajectory(str(path))
    np.testing.assert_allclose(ours.stamp_ns * 1e-9, theirs.timestamps, rtol=0, atol=1e-6)
    np.testing.assert_allclose(ours.pos, theirs.positions_xyz, rtol=0, atol=1e-12)
    quat = theirs.orientations_quat_wxyz[:, [1, 2, 3, 0]]  # ours made unit, as written
    np.testing.assert_allclose(ours.quat, quat / np.linalg.norm(quat, axis=1, keepdims=True),
                               rtol=0, atol=1e-12)
    assert ours.read_as == ('the first 8 of its 11 columns read (t x y z and a quaternion), '
                            'the rest unused',
                            'quaternions read w first, as its header names them',
                            'stamps read as nanoseconds')
    # 17 columns as Kimera (w first, named in a comment) and OKVIS (x first, a bare header
    # line) write them: the same poses
    rows = np.column_stack([ours.stamp_ns, ours.pos, np.zeros((len(ours.pos), 4)),
                            np.full((len(ours.pos), 9), 0.01)]).astype(object)
    rows[:, 0] = ours.stamp_ns
    for header, quat, said in (
            ('#timestamp,x,y,z,qw,qx,qy,qz,vx,vy,vz,bgx,bgy,bgz,bax,bay,baz',
             ours.quat[:, [3, 0, 1, 2]], True),
            ('timestamp, p_WS_W_x, p_WS_W_y, p_WS_W_z, q_WS_x, q_WS_y, q_WS_z, q_WS_w, '
             'v_WS_W_x, v_WS_W_y, v_WS_W_z, b_g_x, b_g_y, b_g_z, b_a_x, b_a_y, b_a_z',
             ours.quat, False)):
        rows[:, 4:8] = quat
        other = read_tum(_write(tmp_path / 'estimate.csv', [header] + [
            ','.join(f'{v:.12g}' if isinstance(v, float) else str(v) for v in row)
            for row in rows]))
        np.testing.assert_array_equal(other.stamp_ns, ours.stamp_ns)
        np.testing.assert_allclose(other.quat, ours.quat, rtol=0, atol=1e-11)
        assert (other.read_as[0].startswith('the first 8 of its 17 columns read')
                and ('quaternions read w first, as its header names them' in other.read_as)
                == said)
    # VINS-Mono's and VINS-Fusion's own CSV, no header: t[ns],x,y,z,qw,qx,qy,qz,vx,vy,vz,
    vins = read_tum(_write(tmp_path / 'vio.csv', [
        f'{t},' + ','.join(f'{v:.5f}' for v in (*p, q[3], *q[:3], 0.0, 0.0, 0.0)) + ','
        for t, p, q in zip(ours.stamp_ns, ours.pos, ours.quat)]))
    np.testing.assert_allclose(vins.quat, ours.quat, rtol=0, atol=1e-4)
    assert vins.read_as[1] == ('quaternions read w first, as every tool writing 11 columns '
                               "writes them (ASL's state CSV, VINS-Mono's and VINS-Fusion's)")
    # a header that names the first 8 columns x first decides, and a comment that names no
    # quaternion does not
    for comment, order in (('# timestamp tx ty tz qx qy qz qw', [0, 1, 2, 3]),
                           ('# written by my VIO', [3, 0, 1, 2])):
        other = read_tum(_write(tmp_path / 'eleven.txt', [comment] + [
            f'{t} ' + ' '.join(f'{v:.9f}' for v in (*p, *q[order], 0.0, 0.0, 0.0))
            for t, p, q in zip(ours.stamp_ns, ours.pos, ours.quat)]))
        np.testing.assert_allclose(other.quat, ours.quat, rtol=0, atol=1e-8)
    # units written apart from their names; a spreadsheet's empty first row
    tum = read_tum(_write(tmp_path / 'units.txt', [
        ',,,,,,,', '# t [s] x [m] y [m] z [m] qw qx qy qz', '1.0 0 0 0 0.5 0.5 0.5 0.5',
        '2.0 0 0 0 1 0 0 0']))
    np.testing.assert_allclose(tum.quat, [[0.5, 0.5, 0.5, 0.5], [0, 0, 0, 1]])


def test_written_poses_read_back_exactly(data_dir, tmp_path):
    tum = read_tum(data_dir / 'euroc_vio' / 'vins_mono' / 'MH_01_easy.txt')
    back = read_tum(write_tum(tmp_path / 'a' / 't.txt', tum.stamp_ns, tum.pos, tum.quat))
    np.testing.assert_array_equal(back.stamp_ns, tum.stamp_ns)
    np.testing.assert_allclose(back.pos, tum.pos, rtol=1e-11, atol=0)
    np.testing.assert_allclose(back.quat, tum.quat, rtol=0, atol=1e-11)
    assert back.summary() == ''


def test_duplicate_backward_non_finite_and_non_unit_rows_are_dropped_and_counted(tmp_path):
    path = _write(tmp_path / 't.txt', [
        '# timestamp tx ty tz qx qy qz qw',
        f'1.0 {POSE}', f'1.1 {POSE}', f'1.1 {POSE}',   # a duplicate
        f'1.2 {POSE}', f'1.15 {POSE}',                  # a step back
        '1.3 nan 0 0 0 0 0 1',                          # not a pose
        '1.4 0 0 0 0 0 0 0',                            # no rotation
        '1.45 1e300 0 0 0 0 0 1',                       # nowhere, squared to infinity
        f'1.5 {POSE}'])
    with warnings.catch_warnings():
        warnings.simplefilter('error')  # no numpy overflow warning leaks
        traj = read_tum(path)
    assert traj.stamp_ns.tolist() == [1_000_000_000, 1_100_000_000, 1_200_000_000,
                                      1_500_000_000]
    assert traj.dropped == {'non-finite rows': 1, 'rows whose quaternion is not a unit one': 1,
                            'rows whose position is beyond 1e+07 m (the first: pose 8)': 1,
                            'duplicate stamps': 1, 'stamps earlier than a previous one': 1}
    assert traj.summary().startswith(f'{path}: 4 poses kept; dropped 1 non-finite rows')


@pytest.mark.parametrize('rows, message', [
    (['1.0 0 0 0 0 0 1'], 'has 7 values, not the 8 of a TUM pose'),
    ([f'1.0 {POSE} 0'], r'has 9 values, not the 8 .*, nor 11, 17 or 20 \(those 8, then'),
    ([f'1.0 {POSE}'] * 2 + [f'abc {POSE}'], 'unparsable line "abc'),  # a header only first
    ([f'abc {POSE}', f'1.0 {POSE}'], 'unparsable line "abc'),  # no header: it holds numbers
    ([f'1.0 {POSE}', f'1.1 {POSE} 0'], 'has 9 values where the first pose has 8'),
    ([f'1.0 {POSE}', f'1.1 {POSE}', f'1.2 {POSE}', f'1e12 {POSE}'],
     'stamps from 1 to 1e[+]12: neither all in seconds'),
    ([f'1e20 {POSE}', f'2e20 {POSE}'], 'stamps up to 2e[+]20: no clock in nanoseconds'),
    ([f'nan {POSE}', f'nan {POSE}'], 'fewer than two usable poses'),
    (['1.0 0 0 zero 0 0 0 1'], 'unparsable line "1.0 0 0 zero'),
    (['# only a comment'], 'no poses'),
    ([f'1.0 {POSE}', f'1.0 {POSE}'], 'fewer than two usable poses')])
def test_a_file_that_is_no_trajectory_is_one_line(tmp_path, rows, message):
    with pytest.raises(DatasetError, match=message):
        read_tum(_write(tmp_path / 't.txt', rows))


def test_a_byte_order_mark_and_crlf_are_read_and_a_byte_not_utf8_is_named(tmp_path):
    """Read a line at a time: the file's first bytes and its line ends as a text editor's."""
    text = '\r\n'.join(['t x y z qw qx qy qz', f'1.0 {POSE}', f'1.1 {POSE}']) + '\r\n'
    path = tmp_path / 't.txt'
    path.write_bytes(b'\xef\xbb\xbf' + text.encode())
    traj = read_tum(path)
    assert traj.stamp_ns.tolist() == [1_000_000_000, 1_100_000_000]
    assert traj.read_as == ('quaternions read w first, as its header names them',)
    path.write_bytes(text.encode() + b'1.2 0 0 0 0 0 0 \xff1\n')
    with pytest.raises(DatasetError, match=f'{len(text) + 16} is not UTF-8'):
        read_tum(path)


def test_a_folder_of_trajectories_is_looked_up_by_recording_name(tmp_path):
    _write(tmp_path / 'a.txt', [f'1.0 {POSE}', f'2.0 {POSE}'])
    _write(tmp_path / 'b.tum', [f'1.0 {POSE}', f'2.0 {POSE}'])
    assert trajectory_file(tmp_path, 'a') == tmp_path / 'a.txt'
    assert trajectory_file(tmp_path, 'b') == tmp_path / 'b.tum'
    assert trajectory_file(tmp_path / 'a.txt', 'anything') == tmp_path / 'a.txt'
    with pytest.raises(DatasetError, match=r'no trajectory of c \(c.txt or c.tum or c.csv; it '
                                           r'holds a.txt, b.tum\)'):
        trajectory_file(tmp_path, 'c')
    _write(tmp_path / 'MH_01.TXT', [f'1.0 {POSE}', f'2.0 {POSE}'])
    assert trajectory_file(tmp_path, 'mh_01') == tmp_path / 'MH_01.TXT'
    _write(tmp_path / 'mh_01.tum', [f'1.0 {POSE}', f'2.0 {POSE}'])  # two alike: neither
    with pytest.raises(DatasetError, match=r'2 trajectories of Mh_01 \(MH_01.TXT, mh_01.tum\): '
                                           'keep one'):
        trajectory_file(tmp_path, 'Mh_01')
    _write(tmp_path / 'a.csv', [f'1.0 {POSE}', f'2.0 {POSE}'])  # a stale file beside: neither
    with pytest.raises(DatasetError, match=r'2 trajectories of a \(a.csv, a.txt\): keep one'):
        trajectory_file(tmp_path, 'a')
    (tmp_path / 'vio').mkdir()
    with pytest.raises(DatasetError, match='it holds none'):
        trajectory_file(tmp_path / 'vio', 'a')


def _yawing_trajectory(path: Path, rate_hz: float = 20.0, yaw_rate: float = 0.3) -> Path:
    """Write the poses write_asl's recording follows as a 20 Hz TUM file, a row twice."""
    t = np.arange(0, 5.0, 1 / rate_hz)
    yaw = yaw_rate * t
    rows = [f'{(T0 * 1e-9 + s):.9f} 0 0 0 0 0 {np.sin(y / 2):.12f} {np.cos(y / 2):.12f}'
            for s, y in zip(t, yaw)]
    return _write(path, rows[:10] + rows[9:])


def test_trajectory_poses_replace_the_recordings_own_and_the_drop_is_said(tmp_path):
    rec_dir = write_asl(tmp_path / 'rec', n_imu=1000, yaw_rate=0.3)
    (tmp_path / 'vio').mkdir()
    _yawing_trajectory(tmp_path / 'vio' / 'rec.txt')
    with pytest.warns(DataWarning, match='dropped 1 duplicate stamps'):
        rec = load_recording(rec_dir, poses=tmp_path / 'vio')
    assert len(rec.gt_stamp_ns) == 100  # 20 Hz, not the folder's own 200 Hz
    with pytest.warns(DataWarning):
        seq = load_sequence(rec_dir, poses=tmp_path / 'vio')
    yaw = 0.3 * (seq.stamp_ns - T0) * 1e-9
    np.testing.assert_allclose(seq.gt_quat[:, 2], np.sin(yaw / 2), atol=1e-4)


def test_poses_and_imu_spanning_less_than_the_norms_moving_mean_are_aligned(tmp_path):
    from denoise_imu_ros.data.pose_alignment import _detrended
    assert _detrended(np.ones(5), 200).tolist() == [0.0] * 5
    seq = load_sequence(write_asl(tmp_path / 'rec', n_imu=300, yaw_rate=0.5), align_poses='auto')
    assert len(seq) > 250  # 1.5 s: aligned (nothing to move), not a traceback
    # no quarter long enough to weigh the frame's noise: not measured (None), not NaN (a
    # JSON report's), and so no frame found significant, as for NaN before
    assert seq.pose_alignment['imu_from_pose_rotation_std_deg'] is None
    from denoise_imu_ros.data.pose_alignment import needs_alignment
    assert not needs_alignment({'time_offset_s': 0.0, 'time_offset_std_s': 1e-4,
                                'imu_from_pose_rotation_deg': 0.5,
                                'imu_from_pose_rotation_std_deg': None})


def test_a_trajectory_in_milliseconds_since_its_start_is_named_so(tmp_path):
    rec_dir = write_asl(tmp_path / 'rec', n_imu=1000, yaw_rate=0.3)
    (tmp_path / 'vio').mkdir()
    _write(tmp_path / 'vio' / 'rec.txt', [f'{50.0 * i:.1f} {POSE}' for i in range(100)])
    for align in ('none', 'auto'):
        with pytest.raises(DatasetError, match=r'every 50\.0 s .*; stamps in milliseconds\?$'):
            load_sequence(rec_dir, poses=tmp_path / 'vio', align_poses=align)


def test_check_data_reads_a_trajectory_and_says_what_it_dropped_in_one_line(tmp_path, capsys):
    rec_dir = write_asl(tmp_path / 'rec', n_imu=1000, yaw_rate=0.3)
    traj = _yawing_trajectory(tmp_path / 'rec.txt')
    main(['check-data', '--input', str(rec_dir), '--poses', str(traj)])
    out = capsys.readouterr()
    assert 'poses 20.0 Hz' in out.out
    assert out.err.startswith(f'warning: {traj}: 100 poses kept; dropped 1 duplicate stamps')
    # read another way, nothing dropped: a note, not a warning
    nano = _write(tmp_path / 'nano.txt', [line.split(' ', 1)[0].replace('.', '') + ' '
                                          + line.split(' ', 1)[1] for line in
                                          traj.read_text().splitlines()[10:]])
    main(['check-data', '--input', str(rec_dir), '--poses', str(nano)])
    assert re.match(rf'note: {nano}: \d+ poses kept; stamps read as nanoseconds\n',
                    capsys.readouterr().err)


def test_the_recordings_own_poses_as_tum_files_give_the_same_recipe(euroc, tmp_path,
                                                                    monkeypatch):
    from denoise_imu_ros.data.load import load_recording as read
    from denoise_imu_ros.learn import train as train_module
    from denoise_imu_ros.learn.config import load_config
    from denoise_imu_ros.learn.recipe import init_recipe
    names = ['MH_01_easy', 'V2_01_easy']
    euroc = _heads(euroc, names, tmp_path / 'euroc', 100.0)  # a training window and more
    for name in names:  # the motion capture, written as a VIO tool writes its trajectory
        rec = read(euroc / name)
        write_tum(tmp_path / f'{name}.txt', rec.gt_stamp_ns, rec.gt_pos, rec.gt_quat)
    own, _ = init_recipe(euroc, names)
    from_files, said = init_recipe(euroc, names, poses=tmp_path)
    assert from_files.pop('poses') == str(tmp_path) and own.pop('poses') is None
    assert any(line.startswith("the poses are a VIO's or SLAM's estimate: train "
                               '--calibration-only too') for line in said)
    # the trajectory's drift is kept out of the model; the bias comes from stillness
    assert [k for k in own if own[k] != from_files[k]] == ['rest_bias', 'recording_bias']
    assert from_files['rest_bias'] and from_files['recording_bias']
    assert any(line.startswith("heading_weight 1: the poses' heading disagrees with the gyro")
               and line.endswith('not above 1.3x: both taught') for line in said)
    assert any(line.startswith('rest_bias and recording_bias on: the poses are a trajectory '
                               'estimate') and '1 of 2 recordings are still' in line
               for line in said)
    # none starting still: nothing measures the bias apart from the drift, and it is said
    _, said = init_recipe(euroc, names[:1], poses=tmp_path)
    assert any(line.startswith('rest_bias off: 0 of 1') and line.endswith(
        'record a few still seconds at the start of each run, and stillness measures the bias '
        'instead') for line in said)
    (tmp_path / 'r.yaml').write_text(f'sequences: {names}\ndata: {euroc}\n'
                                     f'poses: {tmp_path}\n')
    seen = []
    monkeypatch.setattr(train_module, 'load_sequence',
                        lambda *a, **k: seen.append(k['poses']) or load_sequence(*a, **k))
    train_module.load_sequences(load_config(tmp_path / 'r.yaml'))
    assert seen == [str(tmp_path)] * 2


@pytest.mark.parametrize('command', ['eval', 'noise'])
def test_scoring_a_cameras_trajectory_as_the_imus_poses_is_refused_in_one_line(
        command, data_dir, euroc, tmp_path, capsys):
    vins = data_dir / 'euroc_vio' / 'vins_mono'
    assert main([command, '--model', 'euroc', '--data', str(euroc), '--sequences',
                 'MH_01_easy', '--poses', str(vins), '--out', str(tmp_path / 'o')]) == 1
    err = capsys.readouterr().err.splitlines()[-1]  # after a note that it trained on it
    assert err.startswith(f'denoise-imu {command}: error: ') and re.search(
        r'MH_01_easy: poses -9\d\.\d ms off the IMU clock and in a frame 89\.\d\d deg from the '
        r"IMU's: figures against them as they are would be wrong; give --align auto", err)


def test_poses_whose_heading_is_noisier_than_their_tilt_teach_the_tilt_alone(euroc, tmp_path):
    from denoise_imu_ros.data.load import load_recording as read
    from denoise_imu_ros.learn.recipe import init_recipe
    from scipy.spatial.transform import Rotation
    names = ['MH_01_easy', 'V2_01_easy']
    euroc = _heads(euroc, names, tmp_path / 'euroc')
    rng = np.random.default_rng(0)
    for name in names:  # the motion capture, its heading (about the world's z) jittered
        rec = read(euroc / name)
        about = np.zeros((len(rec.gt_quat), 3))
        about[:, 2] = rng.normal(0, 2e-3, len(rec.gt_quat))
        quat = (Rotation.from_rotvec(about) * Rotation.from_quat(rec.gt_quat)).as_quat()
        write_tum(tmp_path / f'{name}.txt', rec.gt_stamp_ns, rec.gt_pos, quat)
    recipe, said = init_recipe(euroc, names, poses=tmp_path)
    assert recipe['heading_weight'] == 0.0
    assert any(line.startswith('heading_weight 0: ') and 'learnt from the tilt alone' in line
               for line in said)


def test_a_vios_drifting_heading_is_seen_over_the_drift_horizons_where_noise_hides_it(
        data_dir, euroc, tmp_path):
    from denoise_imu_ros.data.check import DRIFT_HORIZONS_S
    from denoise_imu_ros.learn.recipe import init_recipe
    from scipy.spatial.transform import Rotation
    names = ['MH_01_easy', 'MH_05_difficult']
    rng = np.random.default_rng(6)
    for name in names:  # VINS-Mono's trajectory with 0.5 deg of white noise on every axis
        vins = read_tum(data_dir / 'euroc_vio' / 'vins_mono' / f'{name}.txt')
        noise = Rotation.from_rotvec(rng.normal(0, np.radians(0.5), (len(vins.quat), 3)))
        write_tum(tmp_path / f'{name}.txt', vins.stamp_ns, vins.pos,
                  (Rotation.from_quat(vins.quat) * noise).as_quat())
    recipe, said = init_recipe(euroc, names, poses=tmp_path)
    # at the first increment the noise, as much in the tilt as in the heading, hides the
    # heading's drift; over 5-20 s the noise does not grow and the drift does
    line = next(line for line in said if line.startswith('heading_weight'))
    assert recipe['heading_weight'] == 0.0 and re.search(
        r'\((\d+) s increments, a drift horizon\)', line).group(1) in {
            f'{h:.0f}' for h in DRIFT_HORIZONS_S}


def test_keyframes_too_sparse_for_the_motion_train_between_their_stamps(
        data_dir, euroc, tmp_path):
    from denoise_imu_ros.learn.recipe import init_recipe
    rng = np.random.default_rng(6)
    names = ['MH_01_easy', 'MH_03_medium', 'V2_01_easy']
    euroc = _heads(euroc, names, tmp_path / 'euroc')
    for name in names:
        vins = read_tum(data_dir / 'euroc_vio' / 'vins_mono' / f'{name}.txt')
        keep = slice(None)
        if name == 'MH_01_easy':  # a SLAM's keyframe trajectory: a pose every 0.2-1.0 s
            t = (vins.stamp_ns - vins.stamp_ns[0]) * 1e-9
            wanted = np.cumsum(rng.uniform(0.2, 1.0, 1000))
            keep = np.unique(np.searchsorted(t, wanted[wanted < t[-1]]))
        write_tum(tmp_path / f'{name}.txt', vins.stamp_ns[keep], vins.pos[keep],
                  vins.quat[keep])
    recipe, said = init_recipe(euroc, names, poses=tmp_path)
    assert recipe['sequences'] == names and recipe['increments_between_poses'] is True
    assert any(re.match(r'increments_between_poses: the poses are too sparse for the motion '
                        r'on MH_01_easy \(.*MH_01_easy -\d+\.\d % about y; limit 1 %\)', line)
               for line in said)
    dense, _ = init_recipe(euroc, names[1:], poses=tmp_path)
    assert dense['increments_between_poses'] is False
