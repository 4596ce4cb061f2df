# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Gravity-aided filters offline: their settings chosen on training data, and their scores.

The product's filter is VQF (:mod:`denoise_imu_ros.pipeline.fusion`); for comparison the
calibrated gyro is also fed to two other standard filters, each from its library:
``imufusion`` (x-io's AHRS, C core) and ``ahrs``'s Madgwick. Every filter's settings are
chosen the same way (``denoise-imu tune-fusion``): on the validation tails of the
model's training recordings (the samples after its training windows, which no training
step saw), the setting with the lowest mean 3-D error wins. Each filter starts at its
tail, as a run starts with its filter: a tail stands for a run no training saw, and a
filter warmed up over the training span would hide what its own start costs (VQF's bias
estimation: docs/results.md). Test sequences are never used. Scores follow
:func:`denoise_imu_ros.core.metrics.fused_errors`: yaw aligned once 1.5 s in, tilt
never. Each model's gyro is its output as it runs, its bias tracked where its file says
so (``crossval --attach`` chooses that).
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any

import ahrs
import imufusion
import numpy as np
from scipy.spatial.transform import Rotation

from ..core.compat import check_baseline
from ..core.errors import DatasetError, ModelFileError
from ..core.limits import check_rate, GRAVITY_M_S2
from ..core.metrics import fused_errors, FusedErrors
from ..core.modelfile import read_model_file, sample_rate
from ..core.records import Sequence
from ..core.rotation import from_gravity
from ..core.schema import JUDGED, judged_on, MAX_ACCEL_BIAS_M_S2, ModelMeta
from ..data.load import load_sequence
from ..learn.checkpoint import load_model, LoadedModel
from ..pipeline.fusion import (fuse, FusionSettings, interval_rates, step_periods,
                               VQF_OWN_DEFAULTS)

TAU_ACC_GRID_S = (0.5, 1.0, 2.0, 3.0, 5.0, 10.0, 20.0, 50.0)   # VQF's accelerometer time constant
IMUFUSION_GAINS = (0.02, 0.05, 0.1, 0.2, 0.5, 1.0)          # its default: 0.5
MADGWICK_GAINS = (0.001, 0.003, 0.01, 0.033, 0.1, 0.3)     # ahrs's default: 0.033
NO_BIAS = (0.0, 0.0, 0.0)
FUSED = {'aoe_deg': 'aoe', 'tilt_deg': 'tilt'}  # a judged figure's FusedErrors field
TILT_LABEL = ", the tilt of VQF's defaults on the raw IMU"  # a filter's with classical_tilt


@dataclass(frozen=True)
class Filter:
    """One filter with its settings: ``vqf`` (tau_acc_s, bias_estimation) or a gain."""

    kind: str                       # vqf, imufusion or madgwick
    tau_acc_s: float = 3.0
    bias_estimation: bool = False
    gain: float = 0.0
    accel_bias_m_s2: tuple[float, float, float] = NO_BIAS  # removed before the filter
    classical_tilt: bool = False  # the tilt of VQF's defaults on the raw IMU (vqf only)

    def __post_init__(self) -> None:
        """Refuse a classical tilt on a filter that has none (only VQF's is composed)."""
        if self.classical_tilt and self.kind != 'vqf':
            raise ValueError(f"the classical tilt is a VQF setting, not {self.kind}'s")

    @property
    def label(self) -> str:
        """Name in tables and model files."""
        removed = ', accel bias removed' if any(self.accel_bias_m_s2) else ''
        if self.kind == 'vqf':
            return (f'vqf tau_acc {self.tau_acc_s:g} s, bias estimation '
                    f'{"on" if self.bias_estimation else "off"}{removed}'
                    + (TILT_LABEL if self.classical_tilt else ''))
        return f'{self.kind} gain {self.gain:g}{removed}'

    @property
    def settings(self) -> FusionSettings:
        """Return the filter's VQF settings, checked (model files are user input)."""
        return FusionSettings(self.tau_acc_s, self.bias_estimation, self.accel_bias_m_s2,
                              self.classical_tilt)

    def as_dict(self) -> dict[str, Any]:
        """Return what a model file stores of it."""
        if self.kind == 'vqf':
            return {'filter': 'vqf', 'settings': self.settings.as_dict()}
        return {'filter': self.kind, 'gain': self.gain,
                'accel_bias_m_s2': list(self.accel_bias_m_s2)}

    @classmethod
    def vqf(cls, settings: FusionSettings) -> Filter:
        """Return VQF with these settings (the inverse of :attr:`settings`)."""
        return cls('vqf', settings.tau_acc_s, settings.bias_estimation,
                   accel_bias_m_s2=settings.accel_bias_m_s2,
                   classical_tilt=settings.classical_tilt)

    @classmethod
    def from_dict(cls, stored: Any, where: str = 'model file') -> Filter:
        """Rebuild a filter from :meth:`as_dict`'s mapping (a model file's: checked)."""
        try:
            kind = stored.get('filter', 'vqf')
            if kind == 'vqf':
                return cls.vqf(FusionSettings(**stored.get('settings', {})))
            if kind not in LABELS:
                raise ValueError(f'unknown filter {kind!r}')
            gain = float(stored['gain'])
            if not (math.isfinite(gain) and gain >= 0):
                raise ValueError(f'gain {gain!r}')
            bias = FusionSettings(accel_bias_m_s2=stored.get('accel_bias_m_s2', NO_BIAS))
        except (AttributeError, KeyError, TypeError, ValueError) as err:
            raise ModelFileError(f'{where}: inconsistent filter settings ({err})') from err
        return cls(kind, gain=gain, accel_bias_m_s2=bias.accel_bias_m_s2)


def grid(kind: str, accel_bias: tuple[float, float, float] | None = None) -> list[Filter]:
    """Every setting tried for a filter, each with and without a fitted accelerometer bias."""
    biases = [NO_BIAS] + ([tuple(accel_bias)] if accel_bias is not None else [])
    if kind == 'vqf':
        return [Filter('vqf', tau, est, accel_bias_m_s2=b)
                for b in biases for est in (False, True) for tau in TAU_ACC_GRID_S]
    gains = IMUFUSION_GAINS if kind == 'imufusion' else MADGWICK_GAINS
    return [Filter(kind, gain=g, accel_bias_m_s2=b) for b in biases for g in gains]


def run(flt: Filter, gyro: np.ndarray, accel: np.ndarray, rate_hz: float,
        stamp_ns: np.ndarray | None = None, raw: np.ndarray | None = None) -> np.ndarray:
    """
    Orientation (N, 4) xyzw at every stamp, stepped to stamp k by samples k - 1 and k.

    The step is at their mean (:func:`~denoise_imu_ros.pipeline.fusion.interval_rates`).

    With ``stamp_ns``, VQF integrates the real intervals as the node does (the baselines
    step by one period: the recordings scored have none missing). ``raw``: the gyro as
    received, for a filter with the classical tilt.
    """
    if flt.kind == 'vqf':
        return fuse(gyro, accel, rate_hz, flt.settings,
                    None if stamp_ns is None else step_periods(stamp_ns, rate_hz), raw)
    accel = accel - np.array(flt.accel_bias_m_s2)  # as fuse does
    rates = interval_rates(np.asarray(gyro, dtype=np.float64))
    if flt.kind == 'madgwick':  # its sample 0 sets the tilt, rate k steps to stamp k
        wxyz = ahrs.filters.Madgwick(gyr=rates, acc=accel, frequency=rate_hz,
                                     gain=flt.gain).Q
    else:
        fusion = imufusion.Ahrs()
        settings = imufusion.AhrsSettings()
        settings.convention, settings.gain = imufusion.CONVENTION_NWU, flt.gain
        settings.gyroscope_range, settings.sample_rate = 0.0, rate_hz  # no range, no rejection
        settings.acceleration_rejection = settings.magnetic_rejection = 0.0
        fusion.set_settings(settings)
        fusion.skip_startup()  # as the others: the first accelerometer sets the tilt
        wxyz = np.empty((len(gyro), 4))
        deg, g = np.degrees(rates), accel / GRAVITY_M_S2  # its units: deg/s and g
        for k in range(len(gyro)):
            if k == 0:
                x, y, z, w = from_gravity(*accel[0])
                fusion.set_quaternion(np.array([w, x, y, z]))
            else:
                fusion.update_no_magnetometer(deg[k], g[k])
            wxyz[k] = fusion.get_quaternion()
    return np.asarray(wxyz)[:, [1, 2, 3, 0]]


def score(seq: Sequence, quat: np.ndarray) -> FusedErrors:
    """Fused errors of an orientation at every stamp of a sequence."""
    t = (seq.stamp_ns - seq.stamp_ns[0]) * 1e-9
    return fused_errors(Rotation.from_quat(quat), Rotation.from_quat(seq.gt_quat),
                        seq.gt_valid, t)


SMOOTHING_S = 0.2  # the poses' second derivative: a cubic fitted over this long


def specific_force(seqs: list[Sequence],
                   end: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """
    Return what the accelerometer read and what it should have, (M, 3) each, from the poses.

    What it should read is the specific force R^T (p'' + g e_z), with p'' the poses'
    acceleration (a smoothed second derivative, Savitzky-Golay), over the samples before
    ``end`` (None: all) of every sequence whose smoothing window holds no ground-truth hole.
    Positions are taken as the IMU's (a lever arm of centimetres adds only w^2 r).
    """
    from scipy.ndimage import binary_erosion
    from scipy.signal import savgol_filter
    read, should = [np.empty((0, 3))], [np.empty((0, 3))]
    for seq in seqs:
        part = seq.tail(0, end)
        window = 2 * int(SMOOTHING_S * part.rate_hz / 2) + 1
        if len(part) <= window:
            continue
        acc = savgol_filter(part.gt_pos, window, 3, deriv=2, delta=1.0 / part.rate_hz, axis=0)
        force = Rotation.from_quat(part.gt_quat).inv().apply(acc + [0.0, 0.0, GRAVITY_M_S2])
        usable = binary_erosion(part.gt_valid, np.ones(window, bool), border_value=False)
        read.append(part.imu[usable, 3:])
        should.append(force[usable])
    return np.vstack(read), np.vstack(should)


def fit_accel_bias(seqs: list[Sequence],
                   end: int | None = None) -> tuple[np.ndarray, int] | None:
    """
    Fit the accelerometer's constant bias (m/s^2, body frame) to the poses; its sample count.

    The median of the reading minus the specific force (:func:`specific_force`). None
    when nothing is usable, or when the fit is out of any IMU's range: poses whose world
    z does not point up, or wrong units.
    """
    read, should = specific_force(seqs, end)
    if not len(read):
        return None
    bias = np.median(read - should, axis=0)
    if np.abs(bias).max() > MAX_ACCEL_BIAS_M_S2:
        return None
    return bias, len(read)


def tune(tails: list[Sequence], gyros: dict[str, list[np.ndarray]], rate_hz: float,
         kinds: dict[str, tuple[str, ...]],
         accel_bias: tuple[float, float, float] | None = None,
         key: str = 'aoe_deg') -> dict[str, Any]:
    """
    Choose every filter's settings for every gyro on the tails: the lowest mean ``key``.

    ``gyros`` maps a source (raw, calibrated, network) to its gyro on each tail;
    ``kinds`` the filters to tune for it; with ``accel_bias`` every setting is tried with
    it removed from the accelerometer too; ``key`` the figure compared (``aoe_deg``, the
    3-D AOE, or ``tilt_deg``, as :func:`~denoise_imu_ros.core.schema.judged_on`
    says). Returns, per source and filter, the chosen filter, its figures (3-D, tilt,
    yaw; the per-axis error std) and every candidate's (the compared figure).
    """
    report: dict[str, Any] = {}
    for source, per_tail in gyros.items():
        for kind in kinds[source]:
            figures = {}
            for flt in grid(kind, accel_bias):
                errs = [score(seq, run(flt, g, seq.imu[:, 3:], rate_hz, seq.stamp_ns))
                        for seq, g in zip(tails, per_tail)]
                figures[flt] = errs
            mean = {f: float(np.mean([getattr(e, FUSED[key]) for e in errs]))
                    for f, errs in figures.items()}
            best = min(mean, key=mean.get)
            errs = figures[best]
            report[f'{source} {kind}'] = dict(best.as_dict(), **{
                'aoe_deg': float(np.mean([e.aoe for e in errs])),
                'tilt_deg': float(np.mean([e.tilt for e in errs])),
                'aoe_yaw_deg': float(np.mean([e.aoe_yaw for e in errs])),
                'orientation_std_rad': np.sqrt(np.mean([e.std_rad ** 2 for e in errs],
                                                       axis=0)).tolist(),
                'candidates': {f.label: m for f, m in mean.items()}})
    return report


# what is tuned for each gyro: the product's filter for all three, the others for the
# gyro a user without the network would feed them
KINDS = {'raw': ('vqf',), 'calibrated': ('vqf', 'imufusion', 'madgwick'), 'network': ('vqf',)}


def training_recordings(net: LoadedModel, data: str | None, what: str
                        ) -> tuple[list[str], int, list[Sequence]]:
    """
    Return a model's training recordings, read, with the sample their validation tail starts at.

    The recordings, their folder and the tail start come from the model file (its recipe
    and run); ``data`` overrides the folder. ``what`` says in errors what the tails are for.
    """
    meta = net.meta
    names, folder, start = meta.train_sequences, data or meta.data, meta.training_span
    if meta.recipe('whole_sequences'):
        raise DatasetError(f'{net.path}: trained on whole recordings (whole_sequences): it '
                           f'has no validation tail to {what} on')
    if not names or start is None:
        raise DatasetError(f'{net.path}: the model file does not name its training '
                           f'recordings and its window: it has no validation tails to {what} '
                           'on')
    if folder is None:
        raise DatasetError(f'{net.path}: the model file does not name the folder of its '
                           'training recordings: pass --data')
    seqs = []
    for name in names:
        seq = load_sequence(f'{folder}/{name}', meta.recipe('imu_topic'),
                            meta.recipe('pose_topic'), meta.recipe('max_gt_gap_s'),
                            align_poses=meta.recipe('align', 'none'), poses=meta.recipe('poses'))
        check_rate(seq.stamp_ns, sample_rate(net), f'{folder}/{name}')  # --data: its own?
        seqs.append(seq)
    if all(len(seq) - start < 2 for seq in seqs):
        raise DatasetError(f'{net.path}: no training recording has a validation tail')
    return list(names), start, seqs


def tune_model(model_spec: str, baseline_spec: str, data: str | None = None,
               progress: bool = True) -> dict[str, Any]:
    """
    :func:`tune` on the validation tails of a model's training recordings.

    The recordings, their folder and the tail start come from the model file
    (:func:`training_recordings`); ``data`` overrides the folder. ``baseline_spec`` is
    the calibrated model.
    """
    net = load_model(model_spec)
    calib = load_model(baseline_spec)
    check_baseline(net, calib)
    meta = net.meta
    names, start, read = training_recordings(net, data, 'choose filter settings')
    tails, seqs, gyros = [], [], {source: [] for source in KINDS}
    for name, seq in zip(names, read):
        if len(seq) - start < 2:
            continue
        whole = {'raw': seq.imu[:, :3], 'calibrated': seq.on_poses(calib.correct(seq.stream)),
                 'network': seq.on_poses(net.correct(seq.stream))}  # the tail's context
        tails.append(seq.tail(start))
        seqs.append(seq)
        for source, gyro in whole.items():
            gyros[source].append(gyro[start:])
        if progress:
            print(f'tail of {name}: {len(seq) - start} samples', flush=True)
    fitted = fit_accel_bias(seqs, start)
    bias = None if fitted is None else tuple(float(b) for b in fitted[0])
    if progress:
        print('accelerometer bias from the poses before the tails: ' + (
            'none usable' if fitted is None else
            f'{np.round(fitted[0], 4).tolist()} m/s^2 ({fitted[1]} samples)'), flush=True)
    key, why = judged_on(meta.heading_weight, 'the choice')
    report = tune(tails, gyros, sample_rate(net), KINDS, bias, key)
    return {'chosen_on': f'validation tails of {", ".join(names)} (from sample {start} on), '
                         f'the lowest mean {JUDGED[key]}' + ('' if why is None else f' ({why})'),
            'judged_on': key,
            'accel_bias': None if fitted is None else {
                'm_s2': list(bias), 'samples': fitted[1],
                'fitted_on': f'poses of {", ".join(names)} before sample {start}'},
            'scored': 'yaw aligned once 1.5 s into each tail, tilt never; mean over tails',
            'filters': report}


def attach(model_spec: str, baseline_spec: str, report: dict[str, Any]) -> None:
    """Store the chosen settings: each model file its own, the network's all of them."""
    from ..core.modelfile import add_metadata
    for spec, source in ((model_spec, 'network'), (baseline_spec, 'calibrated')):
        chosen = report['filters'][f'{source} vqf']
        add_metadata(read_model_file(spec).path, fusion=dict(
            settings=chosen['settings'], orientation_std_rad=chosen['orientation_std_rad'],
            chosen_on=report['chosen_on'], scored=report['scored'],
            accel_bias=report.get('accel_bias'),
            **({'filters': report['filters']} if source == 'network' else {})))


def table(report: dict[str, Any]) -> str:
    """Markdown: the chosen setting of every filter and gyro, its figures on the tails."""
    lines = ['| gyro | filter | chosen | 3-D | tilt | yaw |\n', '|---|---|---|---|---|---|\n']
    for name, r in report['filters'].items():
        source, kind = name.split(' ')
        lines.append(f'| {source} | {kind} | {Filter.from_dict(r).label} | {r["aoe_deg"]:.2f} '
                     f'| {r["tilt_deg"]:.2f} | {r["aoe_yaw_deg"]:.2f} |\n')
    lines.append(f'\nChosen on the {report["chosen_on"]}; {report["scored"]}; degrees.\n')
    fitted = report.get('accel_bias')
    lines.append('Accelerometer bias tried: ' + (
        'none (no usable poses)' if fitted is None else
        f'{[round(b, 4) for b in fitted["m_s2"]]} m/s^2, fitted on the {fitted["fitted_on"]} '
        f'({fitted["samples"]} samples)') + '.\n')
    return ''.join(lines)


DEFAULTS = {'imufusion': Filter('imufusion', gain=0.5), 'madgwick': Filter('madgwick', gain=0.033)}
LABELS = {'vqf': 'VQF', 'imufusion': 'imufusion', 'madgwick': 'Madgwick'}
VQF_DEFAULTS = Filter.vqf(VQF_OWN_DEFAULTS)


def eval_filters(net_meta: ModelMeta, calib_meta: ModelMeta | None, where: str = 'model file'
                 ) -> dict[str, tuple[str, Filter]]:
    """
    Return the fused rows of ``eval``: name -> (gyro source, filter with its settings).

    Each model file's own VQF settings for its gyro; for the raw gyro, the classical rows
    and the other filters the settings ``tune-fusion`` stored in the network's file
    (defaults if none); and what a user runs with no model, VQF's defaults on the raw gyro
    (its own bias estimation on).
    """
    stored = net_meta.fusion.filters

    def chosen(source: str, kind: str) -> Filter:
        if f'{source} {kind}' in stored:
            return Filter.from_dict(stored[f'{source} {kind}'],
                                    f'{where}: fusion.filters.{source} {kind}')
        return DEFAULTS.get(kind, Filter('vqf'))

    def own(meta: ModelMeta) -> Filter:  # a model file's settings for its own gyro
        return Filter.vqf(meta.fusion.chosen)

    rows = {'raw + VQF defaults': ('raw', VQF_DEFAULTS),
            'raw + VQF': ('raw', chosen('raw', 'vqf')),
            'rest bias + VQF': ('rest bias', chosen('raw', 'vqf')),
            'tracker only + VQF': ('tracker only', chosen('raw', 'vqf'))}
    if calib_meta is not None:
        rows['calibrated + VQF'] = ('calibrated', own(calib_meta))
        rows.update({f'calibrated + {LABELS[k]}': ('calibrated', chosen('calibrated', k))
                     for k in ('imufusion', 'madgwick')})
    rows['network + VQF'] = ('network', own(net_meta))
    return rows
