# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Noise figures for a VIO (``denoise-imu noise``): the gyro's error, as Kalibr reports it.

The error of a gyro is measured against the ground truth's own body rate, Log(R_k^T
R_{k+1}) / dt_k, at every stamp where both poses are trusted. Its overlapping Allan
variance (``allantools``) per axis is fitted, by non-negative least squares relative to
each point, with the standard noise model

    sigma^2(tau) = 3 Q^2 / tau^2 + N^2 / tau + B^2 (2 ln 2 / pi) + K^2 tau / 3,

whose terms are the poses' own angle noise (Q: white noise in the ground-truth angle,
slope -1), the gyro's angle random walk (N, slope -1/2), its bias instability (B, flat)
and its rate random walk (K, slope +1/2). N and K are the figures OpenVINS, VINS-Fusion
and Kalibr ask for: ``gyroscope_noise_density`` (rad/s/sqrt(Hz)) and
``gyroscope_random_walk`` (rad/s^2/sqrt(Hz)). Separating Q keeps the poses' noise out of
N; a recording of a few minutes resolves K only roughly. Where the fitted K term is less
than half of the Allan variance at the longest tau (the curve never rises: often K = 0,
which a VIO would read as a bias that never moves), K is given as its upper bound from
the same curve instead (sigma^2 >= K^2 tau / 3 at every tau), and said to be one.

It also checks the covariance the node publishes: the fraction of errors within 1, 2 and
3 of its standard deviations (68.3 / 95.4 / 99.7 % if Gaussian), per sample and over
RESIDUAL_BLOCK-sample increments (the mean rate error of a block against sigma /
sqrt(block), as the model file's sigma was measured on its validation tails). Per sample,
the poses' own angle noise Q dominates the error (differentiated over one period); over
a block it counts once per block, so the block check is the one that says whether
sigma describes the gyro.
"""

from __future__ import annotations

import math
from pathlib import Path
import sys
from typing import Any

import allantools
import numpy as np
from scipy.optimize import nnls

from ..core import jsonio
from ..core.atomic import save_figure, write_text
from ..core.errors import OutputError
from ..core.metrics import increment_residuals, RESIDUAL_BLOCK
from ..core.records import Sequence
from ..core.rotation import log_arrays, relative_arrays

GAUSS = (0.6827, 0.9545, 0.9973)  # fractions within 1, 2, 3 sigma of a normal distribution


def gyro_error(seq: Sequence, gyro: np.ndarray) -> np.ndarray:
    """(M, 3) rad/s: gyro minus the ground truth's body rate, at trusted stamps only."""
    rate = log_arrays(relative_arrays(seq.gt_quat[:-1], seq.gt_quat[1:])) / seq.dt[:, None]
    ok = seq.gt_valid[:-1] & seq.gt_valid[1:]
    return (gyro[:-1] - rate)[ok]


def allan(err: np.ndarray, rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """Octave-spaced taus (s) and the overlapping Allan deviation (K, 3) per axis."""
    curves = [allantools.oadev(np.ascontiguousarray(err[:, i]), rate=rate_hz,
                               data_type='freq', taus='octave') for i in range(3)]
    return curves[0][0], np.stack([c[1] for c in curves], axis=1)


def fit_noise_model(taus: np.ndarray, adev: np.ndarray) -> dict[str, float]:
    """
    Q, N, B, K of the noise model (module docstring) fitted to one Allan curve.

    Points of zero deviation (an axis whose error is exactly zero, as in a synthetic
    recording) carry no relative error to fit: without any other point, every term is 0.
    """
    use = np.isfinite(adev) & (adev > 0)
    taus, var = taus[use], adev[use] ** 2
    if not len(var):
        return dict.fromkeys(('angle_noise_rad', 'noise_density', 'bias_instability',
                              'random_walk'), 0.0)
    basis = np.stack([3 / taus ** 2, 1 / taus, np.full_like(taus, 2 * math.log(2) / math.pi),
                      taus / 3], axis=1)
    coef, _ = nnls(basis / var[:, None], np.ones_like(var))  # relative error at every tau
    q2, n2, b2, k2 = coef
    return {'angle_noise_rad': math.sqrt(q2), 'noise_density': math.sqrt(n2),
            'bias_instability': math.sqrt(b2), 'random_walk': math.sqrt(k2)}


def random_walk(taus: np.ndarray, adev: np.ndarray, fitted: float) -> tuple[float, bool]:
    """
    K of one Allan curve and whether it is only an upper bound.

    The fitted K when its term is at least half the variance at the longest tau; else
    the bound K^2 tau / 3 <= sigma^2(tau), tightest over the curve.
    """
    use = np.isfinite(adev) & (adev > 0)
    if not use.any():
        return 0.0, False
    taus, adev = taus[use], adev[use]
    if fitted ** 2 * taus[-1] / 3 >= 0.5 * adev[-1] ** 2:
        return fitted, False
    return float(np.min(adev * np.sqrt(3 / taus))), True


def figures(err: np.ndarray, rate_hz: float) -> dict[str, Any]:
    """
    Return Kalibr's two gyro figures of the worst axis, the fitted model, the Allan curve.

    An axis whose fit does not resolve its random walk contributes its upper bound
    instead (:func:`random_walk`; ``random_walk_is_bound``: whether the figure is one).
    """
    taus, adev = allan(err, rate_hz)
    fits = [fit_noise_model(taus, adev[:, i]) for i in range(3)]
    walks = [random_walk(taus, adev[:, i], f['random_walk']) for i, f in enumerate(fits)]
    walk, bound = max(walks)
    resolved = [k for k, is_bound in walks if not is_bound and k > 0]
    return {'gyroscope_noise_density': max(f['noise_density'] for f in fits),
            'gyroscope_random_walk': walk, 'random_walk_is_bound': bound and walk > 0,
            'random_walk_resolved': max(resolved) if resolved else None,
            'per_axis': fits, 'taus_s': taus.tolist(), 'adev_rad_s': adev.tolist()}


def covariance_check(err: np.ndarray, std: np.ndarray,
                     block_err: np.ndarray | None = None) -> dict[str, Any]:
    """
    Fractions of the per-axis errors within 1/2/3 standard deviations, and the RMS error.

    ``block_err`` (M, 3) rad/s: mean rate errors over RESIDUAL_BLOCK-sample increments,
    checked against std / sqrt(RESIDUAL_BLOCK) (what white noise of std would give).
    """
    sigma = np.where(std > 0, std, np.nan)
    z = np.abs(err) / sigma
    out = {'std_rad_s': std.tolist(), 'rms_error_rad_s': np.sqrt(np.mean(err ** 2, 0)).tolist(),
           'within_sigma': [float(np.mean(z <= k)) for k in (1, 2, 3)], 'gaussian': GAUSS}
    if block_err is not None and len(block_err):
        block_sigma = sigma / math.sqrt(RESIDUAL_BLOCK)
        zb = np.abs(block_err) / block_sigma
        out['block_samples'] = RESIDUAL_BLOCK
        out['block_within_sigma'] = [float(np.mean(zb <= k)) for k in (1, 2, 3)]
        out['block_rms_over_sigma'] = (np.sqrt(np.mean(block_err ** 2, 0)) / block_sigma
                                       ).tolist()
    return out


def yaml_snippet(pooled: dict[str, dict[str, Any]], where: str,
                 published: dict[str, float] | None = None,
                 published_accel: dict[str, float] | None = None) -> str:
    """
    Return the lines to paste into a Kalibr / OpenVINS / VINS-Fusion IMU configuration.

    One YAML document: the corrected gyro's figures (what ``imu/corrected`` publishes) as
    the keys, the other gyros' as comments for comparison (a key twice is not YAML), and
    where the model gives each message its own variances, those as densities (``published``
    the gyro's, ``published_accel`` the accelerometer's: the median and 95th percentile
    over the recordings) in comments.
    """
    def line(fig: dict[str, Any], comment: str = '') -> str:
        bound = (', an upper bound: the recordings are too short to resolve it'
                 if fig.get('random_walk_is_bound') else '')
        return (f'{comment}gyroscope_noise_density: {fig["gyroscope_noise_density"]:.3e}'
                f'  # rad/s/sqrt(Hz)\n'
                f'{comment}gyroscope_random_walk: {fig["gyroscope_random_walk"]:.3e}'
                f'  # rad/s^2/sqrt(Hz){bound}\n')
    text = (f'# corrected gyro (imu/corrected), measured against ground truth on {where} '
            f'(denoise-imu noise)\n' + line(pooled['corrected']))
    if published is not None:
        text += ("# imu/corrected's own variance per message (fit-variance) as a density: "
                 f"median {published['median']:.3e}, 95th percentile {published['p95']:.3e}"
                 ' rad/s/sqrt(Hz)\n')
    if published_accel is not None:
        text += ("# and its accelerometer's: median "
                 f"{published_accel['median']:.3e}, 95th percentile "
                 f"{published_accel['p95']:.3e} m/s^2/sqrt(Hz)\n")
    for name, fig in pooled.items():
        if name != 'corrected':
            text += f'# the {name} gyro, for comparison:\n' + line(fig, '# ')
    return text


def plot(path: Path, curves: dict[str, dict[str, Any]]) -> None:
    """Allan deviation of each gyro's error, every axis, with the two figures' lines."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 5))
    for (name, f), color in zip(curves.items(), ('C0', 'C1', 'C2', 'C3')):
        taus, adev = np.array(f['taus_s']), np.array(f['adev_rad_s'])
        for i, style in enumerate(('-', '--', ':')):
            ax.loglog(taus, adev[:, i], style, color=color,
                      label=f'{name} ({"xyz"[i]})' if i == 0 else None)
        ax.loglog(taus, f['gyroscope_noise_density'] / np.sqrt(taus), color=color, lw=0.5)  # N
    ax.set_xlabel('tau (s)')
    ax.set_ylabel('Allan deviation of the gyro error (rad/s)')
    ax.grid(True, which='both', alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)


def write(out: Path, report: dict[str, Any]) -> None:
    """results: noise.json, noise.yaml (:func:`yaml_snippet`), allan_<recording>.png."""
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise OutputError(f'{out}: cannot create the output folder ({err.strerror})') from err
    write_text(out / 'noise.json', jsonio.dumps(report, indent=2))
    write_text(out / 'noise.yaml', yaml_snippet(report['pooled'], ', '.join(report['recordings']),
                                                report.get('published_density'),
                                                report.get('published_accel_density')))
    for name, curves in report['recordings'].items():
        plot(out / f'allan_{name}.png', {g: c['figures'] for g, c in curves.items()})


def pooled(per_recording: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """
    Per gyro, what a VIO should be configured with: the worst recording's figures.

    The random walk: the largest the recordings resolve on any axis; if none does, the
    tightest of their upper bounds (each is above the IMU's one value).
    """
    gyros = next(iter(per_recording.values())).keys()
    out = {}
    for g in gyros:
        figs = [r[g]['figures'] for r in per_recording.values()]
        resolved = [f['random_walk_resolved'] for f in figs
                    if f.get('random_walk_resolved') is not None]
        walk = max(resolved) if resolved else min(f['gyroscope_random_walk'] for f in figs)
        out[g] = {'gyroscope_noise_density': max(f['gyroscope_noise_density'] for f in figs),
                  'gyroscope_random_walk': walk, 'random_walk_is_bound': not resolved}
    return out


def markdown(report: dict[str, Any]) -> str:
    """Tables: the figures per recording and gyro, then the covariance check."""
    lines = ['| recording | gyro | noise density (rad/s/√Hz) | random walk (rad/s²/√Hz) | '
             "poses' angle noise (rad) |\n", '|---|---|---|---|---|\n']
    for name, gyros in report['recordings'].items():
        for g, r in gyros.items():
            f = r['figures']
            q = max(a['angle_noise_rad'] for a in f['per_axis'])
            at_most = '≤ ' if f['random_walk_is_bound'] else ''
            lines.append(f'| {name} | {g} | {f["gyroscope_noise_density"]:.3e} | '
                         f'{at_most}{f["gyroscope_random_walk"]:.3e} | {q:.1e} |\n')
    lines.append('\nThe covariance the node publishes (`angular_velocity_covariance`) against '
                 "the corrected gyro's real errors: fraction within 1 / 2 / 3 σ (Gaussian: "
                 "68.3 / 95.4 / 99.7 %), per axis pooled, per sample (the poses' noise "
                 f'dominates) and over {RESIDUAL_BLOCK}-sample increments (σ / '
                 f'√{RESIDUAL_BLOCK}; RMS error over it, 1 if σ is right):\n\n'
                 '| recording | σ x/y/z (rad/s) | RMS error x/y/z (rad/s) | per sample | '
                 f'{RESIDUAL_BLOCK}-sample increments | their RMS / σ x/y/z |\n'
                 '|---|---|---|---|---|---|\n')
    for name, gyros in report['recordings'].items():
        c = gyros['corrected'].get('covariance')
        if c is None:
            continue
        block = c.get('block_within_sigma')
        lines.append(f'| {name} | ' + '/'.join(f'{v:.4f}' for v in c['std_rad_s']) + ' | '
                     + '/'.join(f'{v:.4f}' for v in c['rms_error_rad_s']) + ' | '
                     + '/'.join(f'{100 * v:.1f} %' for v in c['within_sigma']) + ' | '
                     + ('/'.join(f'{100 * v:.1f} %' for v in block) if block else '–') + ' | '
                     + ('/'.join(f'{v:.2f}' for v in c['block_rms_over_sigma']) if block
                        else '–') + ' |\n')
    if report.get('training_fit_note'):
        lines.append(f'\nNote: {report["training_fit_note"]}\n')
    return ''.join(lines)


def noise_report(seqs: list[Sequence], gyros: dict[str, list[np.ndarray]],
                 corrected_std: np.ndarray | None) -> dict[str, Any]:
    """Figures of every gyro on every recording; the check of the corrected gyro's std."""
    per: dict[str, dict[str, Any]] = {}
    for i, seq in enumerate(seqs):
        per[seq.name] = {}
        for g, series in gyros.items():
            err = gyro_error(seq, series[i])
            per[seq.name][g] = {'figures': figures(err, seq.rate_hz)}
            if g == 'corrected' and corrected_std is not None:
                res, duration = increment_residuals(seq.gt_quat, seq.gt_valid, series[i],
                                                    seq.dt, RESIDUAL_BLOCK)
                per[seq.name][g]['covariance'] = covariance_check(
                    err, corrected_std, res / duration[:, None])
    return {'recordings': per, 'pooled': pooled(per),
            'method': 'gyro minus the ground-truth body rate Log(R_k^T R_k+1)/dt_k at trusted '
                      'stamps; overlapping Allan deviation (allantools.oadev, octave taus) '
                      'fitted with 3Q^2/tau^2 + N^2/tau + B^2 2ln2/pi + K^2 tau/3 (NNLS, '
                      'relative to each point); N and K of the worst axis, K as its upper '
                      'bound min sigma(tau) sqrt(3 / tau) where its fitted term is under '
                      'half the variance at the longest tau'}


def noise(model_spec: str, data: str, sequences: list[str], out: str,
          baseline: str | None = None, imu_topic: str | None = None,
          pose_topic: str | None = None, poses: str | None = None,
          align_poses: str = 'none') -> dict[str, Any]:
    """Run the noise figures of raw, calibrated and corrected gyro; write and return them."""
    from ..core.modelfile import gyro_covariance, sample_rate
    from ..data.load import load_sequence
    from ..core.compat import check_baseline
    from ..learn.checkpoint import load_model
    from ..pipeline.covariance import variances
    from ..runtime.settings import Settings
    from .evaluate import check_inputs, default_baseline, recording_names
    from .reports import fitting_note, scored_on_training_samples
    names = recording_names(sequences)  # before the slow part: a name twice is refused
    net = load_model(model_spec)
    baseline = default_baseline(net.meta, baseline)
    calib = load_model(baseline) if baseline is not None else None
    if calib is not None:
        check_baseline(net, calib)
    fitted_on = scored_on_training_samples(net.meta, names, 0)
    note = fitting_note(fitted_on, None) if fitted_on else None  # no --start-sample here
    if note:
        print(f'warning: {note}', file=sys.stderr)
    seqs, gyros = [], {'raw': [], 'calibrated': [], 'corrected': []}
    specs = {'published_density': net.meta.gyro_variance,  # where the node publishes them
             'published_accel_density': net.meta.accel_variance
             if Settings().per_sample_accel(net) else None}
    published: dict[str, list[np.ndarray]] = {}
    for name, short in zip(sequences, names):
        seq = load_sequence(Path(data) / name, imu_topic, pose_topic,
                            min_samples=net.model.receptive_field, poses=poses,
                            align_poses=align_poses, rate_hz=sample_rate(net))
        check_inputs(seq, net, short)
        seqs.append(seq)
        gyros['raw'].append(seq.imu[:, :3])
        if calib is not None:
            gyros['calibrated'].append(seq.on_poses(calib.correct(seq.stream)))
        stream = net.correct(seq.stream)
        gyros['corrected'].append(seq.on_poses(stream))
        for key, spec in specs.items():  # what imu/corrected publishes for these samples
            if spec is not None:
                published.setdefault(key, []).append(
                    variances(stream, seq.stream[:, 3:], sample_rate(net), spec))
    gyros = {g: v for g, v in gyros.items() if v}
    std = np.sqrt(np.diag(np.reshape(gyro_covariance(net), (3, 3))))
    report = noise_report(seqs, gyros, std if std.any() else None)
    report.update(model=str(net.path), baseline=baseline, training_fit_note=note)
    for key, found in published.items():  # a density: a sample's variance times its period
        density = np.sqrt(np.concatenate(found) / sample_rate(net))
        report[key] = {'median': float(np.median(density)),
                       'p95': float(np.percentile(density, 95))}
    write(Path(out), report)
    return report
