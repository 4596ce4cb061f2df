# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""init-recipe: a recipe that follows the data, and leaves out and names what cannot supervise."""

from denoise_imu_ros.cli import main
from denoise_imu_ros.core.errors import DatasetError
from helpers import crop_asl, write_asl
import pytest


def test_init_recipe_follows_the_data(data_dir, tmp_path, capsys):
    from denoise_imu_ros.learn.config import load_config
    rooms = ['dataset-room1_512_16', 'dataset-room5_512_16']
    out = tmp_path / 'recipe.yaml'
    assert main(['init-recipe', '--data', str(data_dir / 'tumvi'), '--sequences', *rooms,
                 '--out', str(out)]) == 0
    cfg = load_config(out)  # a recipe train accepts as it is
    assert cfg.increments == [64, 128]  # the mocap's 16/32 are noise-dominated
    assert cfg.gyro_std_deg == [0.2, 0.2, 0.2] and cfg.align == 'none'
    assert cfg.window % 128 == 0 and 75 < cfg.window / 199.4 <= 80
    assert cfg.sequences == rooms
    assert '16/32 are noise-dominated' in out.read_text().splitlines()[2]
    assert out.read_text().splitlines()[6].startswith('# rest_bias off: 0 of 2 recordings '
                                                      'are still within 5 s of their start')
    assert not cfg.rest_bias  # TUM-VI's rooms start moving
    # its heading disagrees as a VIO's does (the gyro's drift): taught, and the user asked
    assert cfg.heading_weight == 1.0 and out.read_text().splitlines()[7].startswith(
        '# heading_weight 1: the poses are taken as motion capture (not said to be an '
        "estimate); the poses' heading disagrees with the gyro 1.75x")
    assert out.read_text().splitlines()[8].startswith(
        '# supervision: the poses of dataset-room5_512_16 do not lower their own attitude')
    assert 'one recording' not in capsys.readouterr().out  # two: crossval can hold one out
    one = tmp_path / 'one.yaml'
    assert main(['init-recipe', '--data', str(data_dir / 'tumvi'), '--sequences', rooms[0],
                 '--out', str(one)]) == 0
    assert 'one recording: train works, crossval' in capsys.readouterr().out


def test_init_recipe_leaves_out_what_the_poses_cannot_supervise_and_says_so(
        data_dir, tmp_path, capsys, monkeypatch):
    """BROAD: the fast trials under slow motion capture no longer refuse the whole set."""
    from denoise_imu_ros.learn.config import load_config
    if not (data_dir / 'broad').is_dir():
        pytest.skip('BROAD not found')
    trials = ['02_undisturbed_slow_rotation_B', '07_undisturbed_fast_rotation_B',
              '21_undisturbed_fast_combined']
    broad = tmp_path / 'data' / 'broad'
    for trial in trials:  # their first 80 s: the still start and every kind of motion
        crop_asl(data_dir / 'broad' / trial, broad / trial, 80.0)
    out = tmp_path / 'recipe.yaml'
    monkeypatch.chdir(broad.parent)  # a folder given relative to where the user stands
    assert main(['init-recipe', '--data', 'broad', '--sequences', *trials,
                 '--out', str(out)]) == 0
    monkeypatch.chdir(tmp_path)
    cfg = load_config(out)
    assert cfg.data == str(broad.resolve())  # written absolute: it trains from anywhere
    # 07 at 250 deg/s: its poses' 4.7 ms clock offset made every increment "noise" until
    # the label noise was judged with the offset applied; from 128 samples it is clean
    assert cfg.sequences == trials[:2] and not cfg.rest_bias  # measured, not assumed
    assert cfg.increments == [128, 256] and cfg.align == 'auto'
    said = capsys.readouterr().out
    assert ('left out: 21_undisturbed_fast_combined: its poses do not lower its own attitude '
            'error') in said
    assert 'rest_bias off: 2 of 2 recordings are still within 5 s of their start' in said


def test_init_recipe_leaves_out_a_recording_it_cannot_use_and_names_it(euroc, tmp_path):
    from denoise_imu_ros.learn.recipe import init_recipe
    crop_asl(euroc / 'MH_01_easy', tmp_path / 'MH_01_easy', 60.0)
    write_asl(tmp_path / 'flat', n_imu=8000)  # yaw only: no rotation about x
    csv = write_asl(tmp_path / 'broken', n_imu=8000) / 'mav0' / 'imu0' / 'data.csv'
    csv.write_text(csv.read_text().replace('\n', '\nnot a row\n', 1))
    recipe, said = init_recipe(tmp_path, ['flat', 'MH_01_easy', 'broken'])
    assert recipe['sequences'] == ['MH_01_easy']
    assert any(s.startswith(f'left out: {tmp_path / "flat"}: not usable for training: no '
                            'rotation about the IMU x axis') for s in said)
    assert any(s.startswith(f'left out: {csv}:2: expected 7 columns') for s in said)
    assert said[-1] == ('the recipe uses 1 of the 3 recordings given (left out: flat, broken; '
                        'above)')
    with pytest.raises(DatasetError, match=r'^no recording is usable for training: .*flat: not '
                                           r'usable for training: no rotation .*; .*broken.*: '
                                           'expected 7 columns'):
        init_recipe(tmp_path, ['flat', 'broken'])
    with pytest.raises(DatasetError, match='mistyped: no such sequence folder or bag'):
        init_recipe(tmp_path, ['MH_01_easy', 'mistyped'])  # said, not left out
    with pytest.raises(DatasetError, match='one trajectory file for 2 recordings; give a folder'):
        init_recipe(tmp_path, ['MH_01_easy', 'flat'], poses=csv)
    with pytest.raises(DatasetError, match='^--poses .*vio_typo: no such trajectory file or '
                                           'folder$'):
        init_recipe(tmp_path, ['MH_01_easy', 'flat'], poses=tmp_path / 'vio_typo')
