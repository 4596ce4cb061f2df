# Copyright 2026 denoise_imu_ros authors
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.
"""
Offline evaluation (``denoise-imu eval``) and correction (``denoise-imu correct``).

Every method is integrated from the ground-truth attitude at the first stamp with the
convention of :mod:`denoise_imu_ros.metrics`; AOE and ROE skip ground-truth holes.
"""

from __future__ import annotations

import json
from pathlib import Path
import sys
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation
import torch

from .dataset import load_imu, load_sequence
from .errors import DatasetError
from .limits import check_rate
from .metrics import ROE_DISTANCES_M, sequence_errors
from .model import GyroNet
from .modelfile import load_model, shipped_models
from .outputs import atomic_output
from .records import Sequence
from .streaming import StreamingCorrector

CHUNK = 65536  # samples per network call; long recordings are processed in pieces


@torch.no_grad()
def correct_gyro(model: GyroNet, imu: np.ndarray) -> np.ndarray:
    """
    Corrected gyro (N, 3) rad/s for raw samples (N, 6), exactly as one batch call.

    Chunks after the first get receptive_field - 1 samples of real context, so their
    outputs equal those of a single call over the whole recording.
    """
    ctx = model.receptive_field - 1
    u = torch.as_tensor(imu, dtype=torch.float32)
    out = []
    for start in range(0, len(u), CHUNK):
        first = max(0, start - ctx)
        out.append(model(u[None, first:start + CHUNK])[0, start - first:])
    return torch.cat(out).double().numpy()


def correct_to_csv(model_spec: str, source: str, output: str,
                   imu_topic: str | None = None, engine: str = 'batch') -> int:
    """
    Write ``timestamp_ns,wx,wy,wz`` for every IMU sample of an ASL folder or bag.

    ``engine`` is ``batch`` (the torch network over the recording) or ``streaming`` (the
    per-sample numpy engine the online node uses); their outputs agree within 1e-6 rad/s.
    """
    loaded = load_model(model_spec)
    rec = load_imu(source, imu_topic)
    if len(rec.imu) < loaded.model.receptive_field:
        raise DatasetError(f'{source}: {len(rec.imu)} IMU samples, shorter than the '
                           f'receptive field ({loaded.model.receptive_field})')
    check_rate(rec.imu_stamp_ns, loaded.meta.get('sample_rate_hz'), source)
    if engine == 'streaming':
        omega = StreamingCorrector.from_module(loaded.model).process(rec.imu)
    else:
        omega = correct_gyro(loaded.model, rec.imu)
    with atomic_output(output, overwrite=True) as tmp, open(tmp, 'w') as f:
        f.write('timestamp_ns,wx,wy,wz\n')
        for t, w in zip(rec.imu_stamp_ns, omega):
            f.write(f'{t},{w[0]:.9g},{w[1]:.9g},{w[2]:.9g}\n')
    return len(omega)


def score(seq: Sequence, gyro: np.ndarray) -> dict[str, float]:
    """AOE 3-D and yaw (deg) of one method's gyro integrated over a whole sequence."""
    err = sequence_errors(seq, gyro, distances=())[1]
    return {'aoe_deg': err.aoe, 'aoe_yaw_deg': err.aoe_yaw}


def evaluate(model_spec: str, data: str, sequences: list[str], out: str,
             baseline: str | None = None, imu_topic: str | None = None,
             pose_topic: str | None = None, plots: bool = True,
             start_sample: int = 0, align_poses: str = 'none') -> dict[str, Any]:
    """
    Evaluate raw, calibrated and corrected gyro; write JSON, Markdown and PNG files.

    With ``start_sample`` > 0 only the part from that sample on is scored (e.g. the
    validation tail of a training sequence); the networks still see the samples before
    it, and integration starts from the ground truth at ``start_sample``. ``align_poses``
    ``auto`` moves each recording's poses onto the IMU clock and frame first (as
    ``check-data`` estimates them); what was applied is in the report.
    """
    loaded = load_model(model_spec)
    models = {'network': loaded}
    if baseline is None:
        candidate = f'{loaded.meta.get("dataset")}_calibrated'
        baseline = candidate if candidate in shipped_models() else None
    if baseline is not None:
        models = {'calibrated': load_model(baseline), 'network': loaded}
    out_dir = Path(out)
    if start_sample < 0:
        raise DatasetError(f'--start-sample {start_sample}: must be 0 or more')
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise DatasetError(f'{out_dir}: cannot create the output folder ({err.strerror})'
                           ) from err
    results: dict[str, Any] = {}
    roe_all: dict[str, list[np.ndarray]] = {}
    for name in sequences:
        seq = load_sequence(Path(data) / name, imu_topic, pose_topic,
                            min_samples=loaded.model.receptive_field, align_poses=align_poses)
        check_rate(seq.stamp_ns, loaded.meta.get('sample_rate_hz'), name)
        if start_sample >= len(seq) - 1:
            raise DatasetError(f'{name}: {len(seq)} samples, cannot start at {start_sample}')
        gyros = {'raw': seq.imu[:, :3]}
        gyros.update({m: correct_gyro(lm.model, seq.imu) for m, lm in models.items()})
        seq = seq.tail(start_sample)
        gyros = {m: g[start_sample:] for m, g in gyros.items()}
        estimates, results[name] = {}, {}
        for method, gyro in gyros.items():
            estimates[method], err = sequence_errors(seq, gyro)
            results[name][method] = {
                'aoe_deg': err.aoe, 'aoe_yaw_deg': err.aoe_yaw,
                'roe_median_deg': {str(int(d)): v for d, v in err.roe_median().items()}}
            roe_all.setdefault(method, []).append(err.roe)
        if seq.alignment is not None:
            results[name]['pose_alignment'] = seq.alignment
        if plots:
            _plot_sequence(out_dir / f'{name}.png', seq, estimates)
    methods = [m for m in next(iter(results.values())) if m != 'pose_alignment']
    average = {m: {k: float(np.mean([results[s][m][k] for s in results]))
                   for k in ('aoe_deg', 'aoe_yaw_deg')} for m in methods}
    report = {'model': str(loaded.path), 'model_code_version': loaded.meta.get('code_version'),
              'baseline': baseline, 'data': str(data), 'start_sample': start_sample,
              'sequences': results,
              'average': average,
              'conventions': 'R_{k+1} = R_k Exp(w_k dt_k) from ground truth at the first '
                             'stamp; AOE = RMS error angle; yaw = rotation about world z of '
                             'R_est R_gt^T; ROE = median over start stamps; GT holes skipped'}
    crossval = loaded.meta.get('crossval')
    if isinstance(crossval, dict) and 'verdict' in crossval:
        report['crossval'] = crossval
    (out_dir / 'results.json').write_text(json.dumps(report, indent=2))
    table = markdown_table(results, average)
    if 'crossval' in report:
        from .crossval import markdown
        table += '\nThe recipe on recordings it never saw (stored in the model file):\n\n'
        table += markdown(crossval)
    (out_dir / 'results.md').write_text(table)
    if plots:
        _plot_roe(out_dir / 'roe.png', roe_all)
    sys.stdout.write(table)
    return report


def markdown_table(results: dict[str, Any], average: dict[str, Any]) -> str:
    """AOE 3-D / yaw (deg) per sequence and method, plus median ROE at 7/21/35 m."""
    methods = list(average)
    head = '| method | ' + ' | '.join(results) + ' | average |\n'
    lines = [head, '|---' * (len(results) + 2) + '|\n']
    for m in methods:
        cells = [f'{results[s][m]["aoe_deg"]:.2f}/{results[s][m]["aoe_yaw_deg"]:.2f}'
                 for s in results]
        avg = f'**{average[m]["aoe_deg"]:.2f}/{average[m]["aoe_yaw_deg"]:.2f}**'
        lines.append(f'| {m} | ' + ' | '.join(cells) + f' | {avg} |\n')
    lines.append('\nAOE 3-D / yaw in degrees. Median ROE (deg) at '
                 + '/'.join(f'{d:g}' for d in ROE_DISTANCES_M) + ' m:\n\n')
    for m in methods:
        cells = ['/'.join(f'{v:.2f}' for v in results[s][m]['roe_median_deg'].values())
                 for s in results]
        lines.append(f'- {m}: ' + ', '.join(f'{s} {c}' for s, c in zip(results, cells)) + '\n')
    return ''.join(lines)


def _plot_sequence(path: Path, seq: Sequence, estimates: dict[str, Rotation]) -> None:
    """Roll/pitch/yaw against ground truth and the orientation error over time."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    t = (seq.stamp_ns - seq.stamp_ns[0]) * 1e-9
    gt = Rotation.from_quat(seq.gt_quat)
    fig, axes = plt.subplots(4, 1, figsize=(10, 11), sharex=True)
    gt_ypr = np.degrees(np.unwrap(gt.as_euler('ZYX'), axis=0))
    for label, rot, style in [('ground truth', gt, 'k-')] + [
            (m, r, '-') for m, r in estimates.items()]:
        # each curve is drawn as the ground truth's plus its wrapped difference to it:
        # unwrapping curves one by one near pitch +-90 deg put a yaw 360 deg away
        diff = np.degrees(rot.as_euler('ZYX')) - gt_ypr
        ypr = gt_ypr + (diff + 180.0) % 360.0 - 180.0
        for ax, col in zip(axes[:3], (2, 1, 0)):
            ax.plot(t, ypr[:, col], style, label=label, lw=0.8)
        if label != 'ground truth':
            err = np.degrees((gt.inv() * rot).magnitude())
            axes[3].plot(t, np.where(seq.gt_valid, err, np.nan), label=label, lw=0.8)
    for ax, name in zip(axes, ('roll (deg)', 'pitch (deg)', 'yaw (deg)',
                               'orientation error (deg)')):
        ax.set_ylabel(name)
        ax.grid(True, alpha=0.3)
    axes[3].set_yscale('log')
    axes[3].set_ylim(bottom=0.01)
    axes[3].set_xlabel('time (s)')
    axes[0].legend(loc='upper right', fontsize=8)
    axes[0].set_title(seq.name)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _plot_roe(path: Path, roe_all: dict[str, list[dict[float, np.ndarray]]]) -> None:
    """Box plots of relative orientation error per distance, one box per method."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(ROE_DISTANCES_M), figsize=(12, 4))
    for ax, d in zip(axes, ROE_DISTANCES_M):
        data = [np.concatenate([r[d] for r in runs]) for runs in roe_all.values()]
        ax.boxplot(data, showfliers=False)
        ax.set_xticks(range(1, len(data) + 1), list(roe_all), rotation=20)
        ax.set_yscale('log')
        ax.set_title(f'ROE over {d:g} m (deg)')
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
