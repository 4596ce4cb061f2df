# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The rooms' import contracts (setup.cfg) hold, and fail when broken."""

import os
from pathlib import Path
import shutil
import subprocess
import sys

from helpers import ROOT
import pytest

LINT = Path(sys.executable).parent / 'lint-imports'


def _lint(cwd: Path, pythonpath: Path | None = None) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    if pythonpath is not None:
        env['PYTHONPATH'] = str(pythonpath)
    return subprocess.run([str(LINT), '--config', str(ROOT / 'setup.cfg'), '--no-cache'],
                          cwd=cwd, env=env, capture_output=True, text=True, timeout=120)


def test_the_package_keeps_every_contract():
    run = _lint(ROOT)
    assert run.returncode == 0 and 'Contracts: 5 kept, 0 broken.' in run.stdout, run.stdout


@pytest.mark.parametrize('module, line, broken', [
    ('pipeline/online.py', 'import torch  # noqa', 'never import torch BROKEN'),
    ('data/timebase.py', 'from . import check  # noqa', 'nor between rooms BROKEN'),
    ('core/limits.py', 'from ..data import bags  # noqa', 'evaluation BROKEN'),
    ('pipeline/stages.py', 'from ..data import bags  # noqa', 'ROS BROKEN'),
    ('pipeline/vertical.py', 'import scipy  # noqa', 'ROS BROKEN'),
    ('data/check.py', 'import rclpy  # noqa', 'demo use rclpy BROKEN'),
])
def test_a_contract_fails_when_a_module_breaks_it(tmp_path, module, line, broken):
    copy = tmp_path / 'src' / 'denoise_imu_ros'
    shutil.copytree(ROOT / 'denoise_imu_ros', copy,
                    ignore=shutil.ignore_patterns('__pycache__', 'models', 'sample'))
    path = copy / module
    path.write_text(path.read_text() + f'\n\ndef _broken():\n    {line}\n')
    run = _lint(tmp_path, tmp_path / 'src')
    assert run.returncode == 1, run.stdout
    assert broken in run.stdout.split('Broken contracts')[0]
