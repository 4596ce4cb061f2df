# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Every command the README calls torch-free runs where ``import torch`` fails."""

import os
import signal
import subprocess
import sys
import time

from denoise_imu_ros.pipeline.rest_bias import RestBiasSettings
from helpers import DOMAIN, SAMPLE, write_asl, write_untrained_model
import pytest

BLOCKER = '''
import sys


class NoTorch:
    """Make every import of torch fail, as on a robot without it."""

    def find_spec(self, name, path=None, target=None):
        if name == 'torch' or name.startswith('torch.'):
            raise ImportError(f'{name}: torch is not installed here')


sys.meta_path.insert(0, NoTorch())
'''


@pytest.fixture()
def no_torch_env(tmp_path) -> dict:
    """Return an environment whose Python cannot import torch (a sitecustomize)."""
    site = tmp_path / 'site'
    site.mkdir()
    (site / 'sitecustomize.py').write_text(BLOCKER)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(site)] + [p for p in os.environ.get('PYTHONPATH', '').split(os.pathsep) if p]),
        ROS_DOMAIN_ID=str(DOMAIN))
    check = subprocess.run([sys.executable, '-c', 'import torch'], env=env,
                           capture_output=True, text=True)
    assert check.returncode == 1 and 'torch is not installed here' in check.stderr
    return env


def _cli(env: dict, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, '-m', 'denoise_imu_ros.cli', *args], env=env,
                          capture_output=True, text=True, timeout=300)


# runs commands one after another in one interpreter: {name: [args]} -> {name: [code, stdout]}
RUNNER = """
import contextlib, io, json, sys, traceback
from denoise_imu_ros.cli import main
said = {}
for name, args in json.loads(sys.argv[1]).items():
    out = io.StringIO()
    try:
        with contextlib.redirect_stdout(out):
            code = main(args)
    except BaseException:
        code, out = -1, io.StringIO(traceback.format_exc())
    said[name] = [code, out.getvalue()]
print(json.dumps(said))
"""


def test_the_offline_commands_run_without_torch(no_torch_env, tmp_path):
    """convert, process-bag, correct, check-data, init-recipe and rest-model, one interpreter."""
    import json
    from helpers import crop_bag
    rest = write_untrained_model(tmp_path / 'rest.safetensors', {
        'sample_rate_hz': 200.0, 'rest_bias': RestBiasSettings().to_dict()})
    head = str(crop_bag(SAMPLE, tmp_path / 'head', 3.5))  # 700 IMU messages
    commands = {
        'rest-model': (['--like', str(rest), '--out', str(tmp_path / 'r')], 'wrote'),
        'convert': (['--input', str(write_asl(tmp_path / 'asl', n_imu=2000)),
                     '--out', str(tmp_path / 'bag')], 'wrote'),
        'process-bag': (['--input', head, '--out', str(tmp_path / 'out'), '--model', 'euroc'],
                        'wrote'),
        'correct': (['--model', 'euroc', '--input', head, '--out', str(tmp_path / 'c.csv'),
                     '--engine', 'streaming'], 'wrote 700'),
        'check-data': (['--input', str(SAMPLE)], 'verdict: usable for training'),
        'init-recipe': (['--data', str(SAMPLE.parent), '--sequences', SAMPLE.name, '--out',
                         str(tmp_path / 'recipe.yaml')], 'wrote')}
    run = subprocess.run([sys.executable, '-c', RUNNER, json.dumps(
        {name: [name, *args] for name, (args, _) in commands.items()})], env=no_torch_env,
        capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    said = json.loads(run.stdout.splitlines()[-1])
    for name, (_, expect) in commands.items():
        code, out = said[name]
        assert code == 0 and expect in out, (name, out, run.stderr)


def test_play_runs_without_torch(no_torch_env, tmp_path):
    bag = tmp_path / 'bag'
    assert _cli(no_torch_env, 'convert', '--input', str(write_asl(tmp_path / 'asl', n_imu=200)),
                '--out', str(bag)).returncode == 0
    run = _cli(no_torch_env, 'play', '--input', str(bag), '--rate', '10', '--wait', '0')
    assert run.returncode == 0 and 'published 200 IMU messages' in run.stdout, run.stderr


def test_the_node_starts_and_stops_without_torch(no_torch_env):
    node = subprocess.Popen([sys.executable, '-m', 'denoise_imu_ros.runtime.node', '--ros-args',
                             '-p', 'model:=euroc'], env=no_torch_env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    try:
        line, deadline = '', time.monotonic() + 60
        while '/imu/data_raw -> /imu/corrected' not in line and time.monotonic() < deadline:
            line = node.stdout.readline()
            assert line or node.poll() is None, 'the node exited early'
        assert '/imu/data_raw -> /imu/corrected' in line
        node.send_signal(signal.SIGINT)
        out, _ = node.communicate(timeout=30)
        assert node.returncode == 0, out
    finally:
        node.kill()
