# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The disk fills while a command writes.

A real write failure, not a patched function: the commands run in a child process whose
file-size limit (``RLIMIT_FSIZE``) makes every write past 32 KiB fail with an ``OSError``
(Python ignores ``SIGXFSZ``), in Python, in rosbags' writers and in matplotlib alike.
Each command must end with one line naming the output and the cause, exit 1, and leave
no output, no scratch folder and its inputs untouched.
"""

import hashlib
import json
from pathlib import Path
import subprocess
import sys

from denoise_imu_ros.cli import main
from helpers import ROOT, write_asl, write_untrained_model

CHILD = r"""
import contextlib, io, json, resource, sys
from denoise_imu_ros.cli import main
import denoise_imu_ros.evaluation.evaluate, matplotlib.pyplot, torch  # imports write caches
hard = resource.getrlimit(resource.RLIMIT_FSIZE)[1]
resource.setrlimit(resource.RLIMIT_FSIZE, (32 * 1024, hard))
results = []
for argv in json.loads(sys.argv[1]):
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main(argv)
    results.append([code, err.getvalue()])
print(json.dumps(results))
"""


def _digest(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob('*')) if p.is_file()}


def test_a_full_disk_ends_every_writing_command_with_one_line_and_nothing_half_written(
        tmp_path):
    data = tmp_path / 'data'
    write_asl(data / 'rec', n_imu=4000)
    model = write_untrained_model(tmp_path / 'model.safetensors', {'sample_rate_hz': 200.0})
    assert main(['convert', '--input', str(data / 'rec'), '--out', str(data / 'bag')]) == 0
    before = _digest(tmp_path)
    out = tmp_path / 'out'
    out.mkdir()
    commands = {
        'correct': ['correct', '--model', str(model), '--input', str(data / 'rec'),
                    '--out', str(out / 'rec.csv')],
        'convert': ['convert', '--input', str(data / 'rec'), '--out', str(out / 'converted')],
        'process-bag': ['process-bag', '--input', str(data / 'bag'), '--out',
                        str(out / 'processed'),
                        '--model', str(model)],
        'eval': ['eval', '--model', str(model), '--data', str(data), '--sequences', 'rec',
                 '--out', str(out / 'eval')],
        'ensemble': ['ensemble', str(model), str(model), str(model), str(model),
                     '--out', str(out / 'ensemble.safetensors')],
    }
    child = subprocess.run([sys.executable, '-c', CHILD, json.dumps(list(commands.values()))],
                           capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert child.returncode == 0, child.stderr
    for name, (code, err) in zip(commands, json.loads(child.stdout)):
        assert code == 1, (name, err)
        errors = [x for x in err.strip().splitlines()
                  if not x.startswith(('warning: ', 'note: '))]
        assert len(errors) == 1, (name, err)
        assert 'File too large' in err and str(out) in err, (name, err)
    # nothing half-written: no scratch folder, no output file but eval's complete reports
    left = sorted(str(p.relative_to(out)) for p in out.rglob('*'))
    assert all(p == 'eval' or p.startswith('eval/results.') for p in left), left
    for report in (out / 'eval').glob('results.json'):
        json.loads(report.read_text())
    after = {k: v for k, v in _digest(tmp_path).items() if not k.startswith('out/')}
    assert after == before  # the inputs untouched
