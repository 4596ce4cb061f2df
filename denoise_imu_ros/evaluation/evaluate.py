# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Offline evaluation (``denoise-imu eval``): raw, calibrated and corrected gyro integrated.

Every method is integrated from the ground-truth attitude at the first scored stamp with
the convention of :mod:`denoise_imu_ros.core.metrics`; AOE and ROE skip ground-truth
holes. The models, their trackers and the gravity-aided filters run from the recording's
first IMU sample, as the node does, also before its poses or ``--start-sample``.
"""

from __future__ import annotations

from pathlib import Path
import sys
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from .filters import eval_filters, Filter, run, score
from .plots import plot_roe, plot_sequence
from .reports import (crossval_table, eval_table, fitting_note, fused_table, growth_table,
                      scored_on_training_samples)
from ..core import jsonio
from ..core.atomic import write_text
from ..core.compat import check_baseline, check_stream
from ..core.errors import OptionError, OutputError
from ..core.metrics import (align_yaw, error_components, sequence_errors,
                            tilt_growth_deg_min)
from ..core.modelfile import sample_rate, shipped_models
from ..core.records import Sequence
from ..core.schema import ModelMeta, REST_ONLY, tracking_from_dict
from ..data.check import label_noise
from ..data.load import load_sequence
from ..data.pose_alignment import offset_text
from ..data.pose_jumps import JUMP_WINDOW_S
from ..learn.checkpoint import load_model, LoadedModel
from ..pipeline import rest_bias


def default_baseline(meta: ModelMeta, baseline: str | None) -> str | None:
    """Return the calibrated-IMU model to compare with, given or shipped for the dataset."""
    if baseline is not None:
        return baseline
    candidate = f'{meta.dataset}_calibrated'
    return candidate if candidate in shipped_models() else None


def recording_names(sequences: list[str]) -> list[str]:
    """Return the names reports key recordings by; two of one name would overwrite."""
    names = [Path(given).name for given in sequences]  # 'base/' or a path: its name
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise OptionError(f'--sequences: {", ".join(twice)} given twice (recordings are '
                          'reported by name)')
    return names


def gyros_of(seq: Sequence, models: dict[str, LoadedModel]) -> dict[str, np.ndarray]:
    """
    Return the gyro of every method: the classical rows (no model), then each model's.

    Over the recording's whole IMU stream
    (:attr:`~denoise_imu_ros.core.records.Sequence.stream`, the samples before its poses
    included), each model fed as it runs online (its rest-bias settings, if it has them).
    The classical rows: raw; rest bias
    (:func:`~denoise_imu_ros.pipeline.rest_bias.baseline_gyro`); tracker only, that with its
    bias tracked (:func:`~denoise_imu_ros.pipeline.rest_bias.tracker_only_gyro`).
    """
    net, stream = models['network'], seq.stream
    gyros = {'raw': stream[:, :3], 'rest bias': rest_bias.baseline_gyro(net, stream),
             'tracker only': rest_bias.tracker_only_gyro(net, stream)}
    gyros.update({m: lm.correct(stream) for m, lm in models.items()})
    return gyros


def rest_note(rest_input: dict[str, bool], rest_only: bool) -> str:
    """Say what each model was fed (the gyro less its turn-on bias where trained so)."""
    said = [f'the {m} row, {"the gyro less its turn-on bias" if on else "the raw gyro"}'
            for m, on in rest_input.items()]
    return ('\nRest bias: the raw gyro less its turn-on bias, estimated causally from '
            'stillness (pipeline/rest_bias.py). Fed to the models: ' + '; '.join(said) + '.'
            + (' The model is rest-only (no network): its "network" row is the rest bias.'
               if rest_only else '') + '\n')


def reference_noise_deg(seq: Sequence) -> float:
    """
    Return the poses' own rotation noise (deg, 3-D, per pose), as the gyro sees it.

    From the label-noise profile (:func:`~denoise_imu_ros.data.check.label_noise`): the
    residual of increments over about JUMP_WINDOW_S (two poses of a 10 Hz trajectory
    apart at least: shorter ones are interpolated, smooth whatever the poses' noise)
    against the gyro less its fitted bias holds the noise of their two poses and the
    gyro's own error over that span (small beside a VIO's); over sqrt 2 it is one pose's.
    On EuRoC's VIO and SLAM trajectories it is within 0.05 deg of the same figure taken
    against the motion capture (docs/results.md). Poses further apart than half that
    span (a SLAM's keyframes) are compared between their stamps, at the length nearest it
    that spans most of the recording: interpolated, what they miss between stamps would
    count as their noise. Not the poses' drift, which no gyro can tell from its own.
    """
    stamps = np.flatnonzero(seq.pose_at) if seq.pose_at is not None else np.zeros(0)
    sparse = len(stamps) > 1 and np.median(np.diff(stamps)) / seq.rate_hz > JUMP_WINDOW_S / 2
    profile = label_noise(seq, between_poses=bool(sparse))['increments']
    length = min(profile, key=lambda j: abs(j / seq.rate_hz - JUMP_WINDOW_S))
    return float(np.degrees(profile[length]['residual_mrad'] * 1e-3 * np.sqrt(3.0 / 2.0)))


def estimate_note(noise_deg: dict[str, float]) -> str:
    """Say what figures against a VIO's or SLAM's poses can and cannot say."""
    each = ', '.join(f'{name} {v:.2f}' for name, v in noise_deg.items())
    return ("\nReference: a VIO's or SLAM's poses (--poses, --estimated-poses), an estimate, "
            'not ground truth. Its own '
            f'rotation noise per pose, about (against the gyro over {JUMP_WINDOW_S:g} s): '
            f'{each} deg; differences between methods below that are not resolved. Its '
            'drift over a recording is in '
            'every figure above and is not measurable here: on EuRoC, ranking methods '
            "against a VIO's or a SLAM's poses did not rank them as the motion capture did "
            '(docs/results.md, "EuRoC without motion capture").\n')


def check_inputs(seq: Sequence, loaded: LoadedModel, name: str) -> None:
    """Refuse a recording this model cannot score: another rate, unit, or IMU holes."""
    check_stream(seq.stamp_ns, seq.imu, name, sample_rate(loaded),
                 loaded.model.input_std.numpy(), loaded.model.input_mean.numpy())


def evaluate(model_spec: str, data: str, sequences: list[str], out: str,
             baseline: str | None = None, imu_topic: str | None = None,
             pose_topic: str | None = None, plots: bool = True,
             start_sample: int = 0, align_poses: str = 'none',
             poses: str | None = None, estimated: bool = False) -> dict[str, Any]:
    """
    Evaluate raw, calibrated and corrected gyro; write JSON, Markdown and PNG files.

    With ``start_sample`` > 0 only the part from that sample on is scored (e.g. the
    validation tail of a training sequence); the networks still see the samples before
    it, and integration starts from the ground truth at ``start_sample``. ``align_poses``
    ``auto`` moves each recording's poses onto the IMU clock and frame first (as
    ``check-data`` estimates them); what was applied is in the report. ``check`` refuses
    poses found off them (the command line's default). Where the poses are an estimate
    (trajectory files, ``poses``, or ``estimated``: a bag's odometry topic, say), their
    own noise is printed beside the figures.
    """
    names = recording_names(sequences)
    models, baseline = _models(model_spec, baseline)
    loaded = models['network']
    out_dir = Path(out)
    if start_sample < 0:
        raise OptionError(f'--start-sample {start_sample}: must be 0 or more')
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise OutputError(f'{out_dir}: cannot create the output folder ({err.strerror})'
                          ) from err
    fitted_on = scored_on_training_samples(loaded.meta, names, start_sample)
    note = fitting_note(fitted_on, loaded.meta.training_span) if fitted_on else None
    if note:
        print(f'warning: {note}', file=sys.stderr)
    rows = eval_filters(loaded.meta, models['calibrated'].meta if 'calibrated' in models
                        else None, str(loaded.path))
    results: dict[str, Any] = {}
    fused: dict[str, Any] = {}
    noise: dict[str, float] = {}  # the reference's own, where it is an estimate
    roe_all: dict[str, list[np.ndarray]] = {}
    for given, name in zip(sequences, names):
        seq = load_sequence(Path(data) / given, imu_topic, pose_topic,
                            min_samples=loaded.model.receptive_field, align_poses=align_poses,
                            poses=poses, rate_hz=sample_rate(loaded))
        check_inputs(seq, loaded, name)
        if start_sample >= len(seq) - 1:
            raise OptionError(f'{name}: {len(seq)} samples, cannot start at {start_sample}')
        if poses is not None or estimated:
            noise[name] = reference_noise_deg(seq)
        gyros = gyros_of(seq, models)
        seq = seq.tail(start_sample)
        results[name], fused[name], estimates, roe = _score(seq, gyros, rows)
        for method, errors in roe.items():
            roe_all.setdefault(method, []).append(errors)
        if plots:
            plot_sequence(out_dir / f'{name}.png', seq, estimates)
    report = _report(models, baseline, data, start_sample, note, results, fused, rows)
    report['reference_noise_deg'] = noise or None
    _write(out_dir, report, loaded.meta.kind == REST_ONLY)
    if plots:
        plot_roe(out_dir / 'roe.png', roe_all)
    return report


def _models(model_spec: str, baseline: str | None
            ) -> tuple[dict[str, LoadedModel], str | None]:
    """Return the network and, where one is given or shipped, its calibration baseline."""
    loaded = load_model(model_spec)
    baseline = default_baseline(loaded.meta, baseline)
    if baseline is None:
        return {'network': loaded}, None
    models = {'calibrated': load_model(baseline), 'network': loaded}
    check_baseline(loaded, models['calibrated'])
    return models, baseline


def _score(seq: Sequence, gyros: dict[str, np.ndarray],
           rows: dict[str, tuple[str, Filter]]) -> tuple[dict, dict, dict, dict]:
    """
    Score one recording: open-loop figures per gyro, fused figures per filter row.

    ``gyros`` over the whole stream; the filters run over it as the node's, from its first
    sample, and both are scored where ``seq`` has poses. Return the figures, every
    method's orientation estimate (for its plot) and the open-loop relative errors (for
    the ROE plot).
    """
    results, fused, estimates, roe = {}, {}, {}, {}
    t = (seq.stamp_ns - seq.stamp_ns[0]) * 1e-9
    for method, gyro in gyros.items():
        estimates[method], err = sequence_errors(seq, seq.on_poses(gyro))
        tilt = error_components(estimates[method], Rotation.from_quat(seq.gt_quat))[1]
        results[method] = {
            'aoe_deg': err.aoe, 'aoe_yaw_deg': err.aoe_yaw, 'tilt_deg': err.tilt,
            'tilt_growth_deg_min': tilt_growth_deg_min(t, tilt, seq.gt_valid),
            'roe_median_deg': {str(int(d)): v for d, v in err.roe_median().items()}}
        roe[method] = err.roe
    for method, (source, flt) in rows.items():
        quat = seq.on_poses(run(flt, gyros[source], seq.stream[:, 3:], seq.rate_hz,
                                seq.stream_stamp_ns, gyros['raw']))
        err = score(seq, quat)
        fused[method] = {
            'filter': flt.label, 'aoe_deg': err.aoe, 'tilt_deg': err.tilt,
            'aoe_yaw_deg': err.aoe_yaw, 'tilt_growth_deg_min': err.tilt_growth_deg_min}
        estimates[method] = align_yaw(Rotation.from_quat(quat),
                                      Rotation.from_quat(seq.gt_quat), err.start)
    if seq.pose_alignment is not None:
        results['pose_alignment'] = seq.pose_alignment
    return results, fused, estimates, roe


def _report(models: dict[str, LoadedModel], baseline: str | None, data: str,
            start_sample: int, note: str | None, results: dict[str, Any],
            fused: dict[str, Any], rows: dict[str, Any]) -> dict[str, Any]:
    """Return ``eval``'s JSON report: every recording's figures and their means."""
    loaded = models['network']
    methods = [m for m in next(iter(results.values())) if m != 'pose_alignment']
    average = {m: {k: float(np.mean([results[s][m][k] for s in results]))
                   for k in ('aoe_deg', 'aoe_yaw_deg', 'tilt_deg')} for m in methods}
    fused_average = {m: {k: float(np.mean([fused[s][m][k] for s in fused]))
                         for k in ('aoe_deg', 'tilt_deg', 'aoe_yaw_deg')} for m in rows}
    report = {'model': str(loaded.path), 'model_code_version': loaded.meta.code_version,
              'baseline': baseline,
              'rest_bias_input': {m: lm.meta.rest_bias is not None for m, lm in models.items()},
              'bias_tracking': {m: lm.meta.bias_tracking.as_dict()
                                for m, lm in models.items() if lm.meta.bias_tracking},
              'data': str(data), 'start_sample': start_sample,
              'training_fit_note': note,
              'sequences': results,
              'average': average,
              'fused': fused, 'fused_average': fused_average,
              'conventions': 'R_{k+1} = R_k Exp(w_k dt_k) from ground truth at the first '
                             'stamp; AOE = RMS error angle; yaw = rotation about world z of '
                             'R_est R_gt^T; tilt = angle between the estimated and the true '
                             'vertical; ROE = median over start stamps; GT holes skipped. '
                             'Fused (gravity-aided) rows: the filter starts at the first IMU '
                             'sample (before the poses and the start sample too), its yaw is '
                             'aligned to the ground truth once 1.5 s into the scored part, '
                             'its tilt never; scored from there on.'}
    if loaded.meta.crossval is not None and loaded.meta.crossval.verdict:
        report['crossval'] = loaded.meta.crossval.report
    return report


def _moved_note(results: dict[str, Any]) -> str:
    """Say the clock offset and frame rotation ``--align auto`` applied to each recording."""
    said = []
    for name, r in results.items():
        if 'pose_alignment' in r:
            turn = Rotation.from_quat(r['pose_alignment']['imu_from_pose_rotation_xyzw'])
            said.append(f'{name} {offset_text(r["pose_alignment"]["time_offset_s"])}, '
                        f'{np.degrees(turn.magnitude()):.2f} deg')
    return ("\nPoses moved onto the IMU's clock and frame first (--align auto; t_imu = t_pose "
            f'+ offset): {"; ".join(said)}.\n' if said else '')


def _write(out_dir: Path, report: dict[str, Any], rest_only: bool) -> None:
    """Write ``results.json`` and ``results.md``; print the tables."""
    write_text(out_dir / 'results.json', jsonio.dumps(report, indent=2))
    results, fused = report['sequences'], report['fused']
    table = (eval_table(results, report['average'])
             + fused_table(fused, report['fused_average']) + growth_table(results, fused))
    table += rest_note(report['rest_bias_input'], rest_only)
    for m, t in report['bias_tracking'].items():
        tracking = tracking_from_dict(t)
        table += (f"The {m} row tracks its output's bias at rest and in motion (VQF, "
                  f'{tracking.describe()}, '
                  'chosen by crossval on recordings its folds never trained on) and removes '
                  'it, as online.\n')
    if report['start_sample']:
        table += f'\nScored from sample {report["start_sample"]} on of every recording.\n'
    table += _moved_note(results)
    if report['training_fit_note']:
        table += f'\nNote: {report["training_fit_note"]}\n'
    if report['reference_noise_deg']:
        table += estimate_note(report['reference_noise_deg'])
    if 'crossval' in report:
        table += '\nThe recipe on recordings it never saw (stored in the model file):\n\n'
        table += crossval_table(report['crossval'])
    write_text(out_dir / 'results.md', table)
    sys.stdout.write(table)
