# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The README's "Train on your robot", end to end, on robot-like bags made from EuRoC."""

import json
import subprocess
import sys

from denoise_imu_ros.cli import main
from denoise_imu_ros.core.modelfile import read_model_file
from denoise_imu_ros.data.bags import read_bag
from denoise_imu_ros.learn.checkpoint import load_model
from denoise_imu_ros.learn.config import load_config
from denoise_imu_ros.runtime.advice import deployment_warning
from diagnostic_msgs.msg import DiagnosticStatus
from helpers import imu_msg, ROOT
import numpy as np
from ros_harness import Harness

SCRIPT = ROOT / 'scripts' / 'fixtures' / 'robot_examples.py'
TOPICS = ['--imu-topic', '/imu/data_raw', '--pose-topic', '/vio/pose']


def test_train_on_your_robot_at_100_hz_with_20_hz_poses(euroc, tmp_path, capsys):
    from helpers import crop_asl
    bags, names = tmp_path / 'bags', ['V1_02_medium', 'V2_01_easy', 'V1_03_difficult']
    for name in names:  # their first 70 s
        crop_asl(euroc / name, tmp_path / 'asl' / name, 70)
    subprocess.run([sys.executable, str(SCRIPT), 'euroc100', str(tmp_path / 'asl'), str(bags),
                    '--sequences', *names], check=True, capture_output=True)
    # check-data: the rates, the paper's increments at this rate, a usable recording
    assert main(['check-data', '--input', str(bags / 'V1_02_medium'), *TOPICS, '--json']) == 0
    report = json.loads(capsys.readouterr().out.splitlines()[-1])
    assert abs(report['imu_rate_hz'] - 100) < 0.5 and abs(report['pose_rate_hz'] - 20) < 0.5
    assert report['paper_increments'] == [8, 16] and report['usable'] == 'yes'
    assert abs(report['time_offset_s']) < 1e-3 and report['imu_from_pose_rotation_deg'] < 0.2
    # init-recipe: window and increments follow the rate
    recipe = tmp_path / 'my_robot.yaml'
    assert main(['init-recipe', '--data', str(bags), '--sequences', 'V1_02_medium',
                 'V2_01_easy', *TOPICS, '--out', str(recipe)]) == 0
    cfg = load_config(recipe)
    assert cfg.increments == [8, 16] and cfg.window % 16 == 0 and cfg.window <= 8000
    # a short run: the user's edit of the recipe
    text = recipe.read_text().replace('steps: 1800', 'steps: 20')
    recipe.write_text(text.replace('swa_start: 1200', 'swa_start: 15'))
    # train, then crossval with the same recipe, attached to the model
    model = tmp_path / 'my_robot.safetensors'
    assert main(['train', '--recipe', str(recipe), '--workers', '1', '--out', str(model),
                 '--quiet']) == 0
    assert main(['crossval', '--recipe', str(recipe), '--workers', '1', '--attach',
                 str(model), '--quiet']) == 0  # as long as the model: the folds judge it
    loaded = load_model(model)
    assert abs(loaded.meta.sample_rate_hz - 100) < 0.5
    assert set(loaded.meta.crossval.report['recordings']) == {'V1_02_medium', 'V2_01_easy'}
    # eval on a recording it never saw: the network beats the raw gyro by far
    out = tmp_path / 'eval'
    capsys.readouterr()
    assert main(['eval', '--model', str(model), '--data', str(bags), '--sequences',
                 'V1_03_difficult', *TOPICS, '--out', str(out), '--no-plots']) == 0
    figures = json.loads((out / 'results.json').read_text())['average']
    assert figures['network']['aoe_deg'] < figures['raw']['aoe_deg'] / 4
    # a 200 Hz recording is refused by the 100 Hz model (the one rate policy)
    assert main(['correct', '--model', str(model), '--input', str(euroc / 'V1_03_difficult'),
                 '--out', str(tmp_path / 'c.csv')]) == 1
    assert 'IMU rate 200.0 Hz, the model was trained at 100.0 Hz' in capsys.readouterr().err
    # the node runs it on the 100 Hz stream: no rate error, the batch network's output
    rec = read_bag(bags / 'V1_03_difficult', '/imu/data_raw', '/vio/pose')
    n = 700
    h = Harness(model)
    try:
        h.send([imu_msg(t, r[:3], r[3:]) for t, r in zip(rec.imu_stamp_ns[:n], rec.imu[:n])])
        h.diagnostics.clear()  # a report from before the first message says 'no input yet'
        h.spin_until(lambda: h.diagnostics, timeout=3.0)
        assert abs(h.node.input_rate_hz() - 100) < 0.5
        # no rate error; a warning only if the model's own verdict says not to deploy it
        warning = deployment_warning(read_model_file(model))
        for status in (s for d in h.diagnostics for s in d.status):
            assert status.level == DiagnosticStatus.OK or (
                status.level == DiagnosticStatus.WARN and status.message == warning)
        assert h.node.attitude_withheld == 0 and len(h.attitude) == n
        got = np.array([[m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z]
                        for m in h.corrected])
        # as the batch network fed what the recipe trained it on
        np.testing.assert_allclose(got, loaded.correct(rec.imu[:n]), atol=1e-6)
    finally:
        h.close()
