# Copyright 2026 denoise_imu_ros authors
# Licensed under the Apache License, Version 2.0
"""check-data: rates, holes and the label-noise profile that picks increment lengths."""

import dataclasses
import json

from denoise_imu_ros.cli import main
from denoise_imu_ros.dataset import align, load_sequence, read_asl
from denoise_imu_ros.quality import check_sequence
import numpy as np
from scipy.spatial.transform import Rotation
from test_dataset import write_asl


def test_clean_and_jittery_ground_truth_are_told_apart(tmp_path):
    rec = read_asl(write_asl(tmp_path / 's', n_imu=6000, gt_rate=120.0, gt_dir='mocap0',
                             gt_hole=(10.0, 11.0), gyro_bias=0.01))
    clean = check_sequence(align(rec), rec.gt_stamp_ns)
    assert abs(clean['gyro_bias_deg_s'][2] - np.degrees(0.01)) < 1e-3
    assert clean['noise_dominated_increments'] == []
    assert clean['pose_holes'] == 1 and 0.9 < clean['pose_longest_hole_s'] < 1.1
    assert abs(clean['pose_rate_hz'] - 120.0) < 0.5 and abs(clean['imu_rate_hz'] - 200) < 0.1
    # 3 mrad of white jitter on every pose: short increments measure it, not the gyro
    rng = np.random.default_rng(0)
    jitter = Rotation.from_rotvec(rng.normal(0, 3e-3, (len(rec.gt_quat), 3)))
    noisy_rec = dataclasses.replace(
        rec, gt_quat=(Rotation.from_quat(rec.gt_quat) * jitter).as_quat())
    noisy = check_sequence(align(noisy_rec), rec.gt_stamp_ns)
    assert {16, 32} <= set(noisy['noise_dominated_increments'])
    assert noisy['shortest_clean_increment'] in (64, 128, 256)
    assert noisy['verdict'].startswith('increments of 16 and 32 samples are dominated')


def test_check_data_on_real_recordings(data_dir, capsys):
    assert main(['check-data', str(data_dir / 'tumvi' / 'dataset-room1_512_16'),
                 '--json']) == 0
    tumvi = json.loads(capsys.readouterr().out.splitlines()[-1])
    assert {16, 32} <= set(map(int, tumvi['noise_dominated_increments']))
    seq = load_sequence(data_dir / 'euroc' / 'V1_01_easy')  # 20 Hz corrected poses
    euroc = check_sequence(seq, read_asl(data_dir / 'euroc' / 'V1_01_easy').gt_stamp_ns)
    assert 19.5 < euroc['pose_rate_hz'] < 20.5
    assert not {16, 32} & set(euroc['noise_dominated_increments'])
