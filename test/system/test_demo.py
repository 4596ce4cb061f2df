# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The live demo: node, player and monitor as separate processes."""

from helpers import DOMAIN


def test_live_demo_runs_node_player_and_monitor(tmp_path, monkeypatch, capsys):
    from denoise_imu_ros import demo
    monkeypatch.setenv('ROS_DOMAIN_ID', str(DOMAIN))
    assert demo.main(['--model', 'euroc', '--rate', '2', '--seconds', '10',
                      '--out', str(tmp_path)]) == 0  # 10 s of the bag in 5 s
    out = capsys.readouterr().out
    assert '2000/2000 samples corrected live over DDS' in out, out
    rms = {line.split(':')[0].strip(): float(line.split(':')[1].split('/')[0])
           for line in out.splitlines() if ' / ' in line and line.startswith('  ')}
    assert set(rms) == {'raw gyro', 'calibrated IMU', 'gyro_denoiser imu/attitude',
                        'calibrated IMU + VQF', 'gyro_denoiser imu/data'}
    assert rms['gyro_denoiser imu/attitude'] < rms['raw gyro'] / 10
    assert rms['calibrated IMU'] < rms['raw gyro'] / 10  # the baseline a user would use
    # the orientation a robot should use, beside the standard filter it would otherwise run
    assert rms['gyro_denoiser imu/data'] < 3.0 and rms['calibrated IMU + VQF'] < 3.0
    for png in ('live_attitude_error.png', 'live_fused_error.png'):
        assert (tmp_path / png).read_bytes()[:4] == b'\x89PNG'


def test_a_bad_rate_is_one_line_and_starts_no_node(tmp_path, monkeypatch, capsys):
    import subprocess
    from denoise_imu_ros import demo
    monkeypatch.setenv('ROS_DOMAIN_ID', str(DOMAIN))
    started = []
    monkeypatch.setattr(subprocess, 'Popen', lambda *a, **k: started.append(a))
    for argv in (['--rate', '0'], ['--seconds', '0']):
        assert demo.main(argv + ['--out', str(tmp_path)]) == 1
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and err.startswith('denoise-imu-demo: error:')
    assert started == []  # nothing left running


def test_the_demos_baselines_run_a_models_own_filter_classical_tilt_included(tmp_path, data_dir):
    """broad_calibrated's filter takes its tilt from the raw IMU: the demo feeds it that."""
    from denoise_imu_ros.core.modelfile import read_model_file
    from denoise_imu_ros.data.load import load_sequence
    from denoise_imu_ros.demo import _baselines
    from helpers import crop_asl
    import numpy as np
    assert read_model_file('broad_calibrated').meta.fusion.chosen.classical_tilt
    trial = crop_asl(data_dir / 'broad' / '03_undisturbed_slow_rotation_C', tmp_path / 't', 20.0)
    seq = load_sequence(trial)
    baselines = _baselines('broad_network', seq)
    assert baselines.calibrated_vqf.shape == (len(seq.gt_quat), 4)
    assert np.isfinite(baselines.calibrated_vqf).all()
