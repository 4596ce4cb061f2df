# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Training recipes: every key's type and range checked, the machine's share, clear refusals."""

from denoise_imu_ros.cli import main
from denoise_imu_ros.core.errors import TrainingError
from denoise_imu_ros.learn.config import load_config, machine_share
from denoise_imu_ros.learn.train import resolve_device
import pytest
import torch


def test_config_typos_and_bad_windows_are_refused(tmp_path):
    (tmp_path / 'typo.yaml').write_text('sequences: [a]\nlearning_rate: 0.1\n')
    with pytest.raises(TrainingError, match=r"unknown keys \['learning_rate'\]"):
        load_config(tmp_path / 'typo.yaml')
    (tmp_path / 'w.yaml').write_text('sequences: [a]\nwindow: 1000\n')
    with pytest.raises(TrainingError, match='multiple of 32'):
        load_config(tmp_path / 'w.yaml')
    (tmp_path / 's.yaml').write_text('sequences: [a]\nselect: swa\nswa_start: 0\n')
    with pytest.raises(TrainingError, match='swa needs swa_start > 0'):
        load_config(tmp_path / 's.yaml')
    (tmp_path / 'l.yaml').write_text('sequences: [a]\nsteps: 10\nswa_start: 20\n')
    with pytest.raises(TrainingError, match='swa_start 20 is after the last step 10'):
        load_config(tmp_path / 'l.yaml')
    (tmp_path / 'p.yaml').write_text('sequences: [a, b]\nworkers: 0\n')
    with pytest.raises(TrainingError, match='workers must be at least 1'):
        load_config(tmp_path / 'p.yaml')
    assert load_config(tmp_path / 'p.yaml', workers=8).workers == 2  # one per sequence
    (tmp_path / 'd.yaml').write_text('sequences: [a, b]\n')
    assert load_config(tmp_path / 'd.yaml', device='cpu').device == 'cpu'
    with pytest.raises(TrainingError, match="device 'tpu': not a torch device"):
        load_config(tmp_path / 'd.yaml', device='tpu')
    # whether the device exists is known to torch only: checked where training starts
    assert load_config(tmp_path / 'd.yaml', device='cuda:1').device == 'cuda:1'
    if not torch.cuda.is_available():
        with pytest.raises(TrainingError, match='torch sees no CUDA GPU'):
            resolve_device('cuda')
        assert resolve_device(load_config(tmp_path / 'd.yaml').device) == 'cpu'  # no GPU


@pytest.mark.parametrize('recordings, cores, share', [
    (6, 2, (2, 2)), (6, 4, (3, 4)), (6, 16, (6, 16)), (9, 2, (2, 2)), (1, 8, (1, 8)),
    (6, 1, (1, 1))])
def test_automatic_workers_give_the_busiest_the_fewest_recordings(recordings, cores, share):
    assert machine_share(recordings, cores) == share


def test_workers_and_threads_auto_follow_the_machine(tmp_path, monkeypatch):
    from denoise_imu_ros.learn import config as config_module
    monkeypatch.setattr(config_module, 'usable_cores', lambda: 4)
    (tmp_path / 'a.yaml').write_text('sequences: [a, b, c, d, e, f]\nworkers: auto\n'
                                     'threads: auto\n')
    cfg = load_config(tmp_path / 'a.yaml')
    assert (cfg.workers, cfg.threads) == (3, 4)
    assert load_config(tmp_path / 'a.yaml', workers=1).workers == 1  # --workers wins


def test_workers_option_takes_a_count_or_auto(capsys):
    with pytest.raises(SystemExit):
        main(['train', '--recipe', 'x.yaml', '--workers', '0'])
    assert "'0': a positive number of processes, or auto" in capsys.readouterr().err


@pytest.mark.parametrize('text, message', [
    ('steps: three', 'steps must be int'),
    ('steps: 3.7', 'steps must be int'),
    ('lr: -0.01', 'lr must be above 0'),
    ('gyro_std_deg: [1, 2]', 'gyro_std_deg must be three positive values'),
    ('val_every: 0', 'val_every must be at least 1'),
    ('calibration_only: "no"', 'calibration_only must be bool'),
    ('dropout: 1.5', 'dropout must be at least 0 and below 1'),
    ('increments: [16, 32.5]', r'increments must be list\[int\]'),
    ('42', 'a training config is a mapping of keys, not int'),
    ('seed: 18446744073709551616', 'seed must be at least 0 and below 4294967296'),
    ('seed: -1', 'seed must be at least 0'),
    ('window: 64', 'skip_blocks 5 leaves no 32-sample increment of a 64-sample window'),
    ('align: {time_offset_s: 0.01, imu_from_pose_rotation_xyzw: [0, 0, 0, 0]}',
     'align must be none, auto or a mapping'),
    ('align: {time_offset_s: .nan, imu_from_pose_rotation_xyzw: [0, 0, 0, 1]}',
     'align must be none, auto or a mapping'),
    ('increments: [0, 32]', 'increments must be rising powers of two'),
    ('increments: [16, 24]', 'increments must be rising powers of two'),
    ('increment_weights: [-1.0, -0.5]', r'increment_weights must be positive, not \[-1.0'),
    ('increment_weights: [1.0, 0]', 'increment_weights must be positive'),
    ('lr_min: 1.0', 'lr_min 1 is above lr 0.01'),
    ('sequences: [a, b, a]', r"sequences listed more than once: \['a'\]"),
    ('recording_bias: true', 'recording_bias needs rest_bias'),
])
def test_recipe_values_of_the_wrong_type_or_range_are_refused(tmp_path, text, message):
    (tmp_path / 'r.yaml').write_text(('sequences: [a]\n' if ':' in text else '') + text + '\n')
    with pytest.raises(TrainingError, match=message):
        load_config(tmp_path / 'r.yaml')


def test_command_line_values_are_named_as_options_and_yaml_exponents_read_as_numbers(
        tmp_path):
    (tmp_path / 'r.yaml').write_text('sequences: [a]\nselect: swa\nswa_start: 1200\n'
                                     'lr: 1e-2\nlr_min: 1E-4\ngyro_std_deg: [1e0, 2, 5.]\n')
    cfg = load_config(tmp_path / 'r.yaml')  # YAML 1.1 reads 1e-2 as a string
    assert (cfg.lr, cfg.lr_min, cfg.gyro_std_deg) == (0.01, 1e-4, [1.0, 2, 5.0])
    with pytest.raises(TrainingError, match=r"^--steps 30: ends before the recipe's "
                                            'swa_start 1200'):
        load_config(tmp_path / 'r.yaml', steps=30)
    with pytest.raises(TrainingError, match='^--seed: seed must be at least 0'):
        load_config(tmp_path / 'r.yaml', seed=-3)


def test_a_binary_recipe_is_a_clear_error(tmp_path):
    (tmp_path / 'r.yaml').write_bytes(b'\xff\xfe\x00garbage')
    with pytest.raises(TrainingError, match='cannot read training config'):
        load_config(tmp_path / 'r.yaml')
