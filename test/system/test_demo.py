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
    assert '2000/2000 samples corrected live over DDS' in out
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
