# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Cross-recording validation (``denoise-imu crossval``): does a recipe hold on new days.

The validation tails come from the training recordings, so they cannot say how a model
does on a recording it never saw (another bias, another temperature). Here the recipe's
recordings are split into folds by recording; each fold trains the network and the
12-parameter calibrated-IMU baseline on the other recordings and scores the held-out
ones whole (AOE from the ground truth at their first stamp), against the classical
pipeline a practitioner runs with no training: plain integration of the input gyro, the
input gyro less its turn-on bias (estimated from stillness, ``pipeline/rest_bias.py``), and
that with its remaining bias tracked ("tracker only"). The verdict says which of the five
to deploy; a learnt one never loses to the classical pipeline on one recording by more
than LOSS_LIMIT.

The output bias tracking (:class:`~denoise_imu_ros.core.schema.BiasTracking`) is chosen
here too, on recordings no model saw: the shipped model's, for the network, for the
calibration and for the tracker only, is the candidate of lowest mean AOE over every
held-out recording
(none among them); the figures of a fold's recordings use the candidate the other folds'
recordings choose, so that no figure was picked on itself. Where the folds leave a power-on
out, ``imu/data``'s filter is chosen the same way (:func:`_fusion`): another power-on may bring
another accelerometer bias, and ``tune-fusion``'s validation tails share the training's.

The accelerometer is judged apart (:func:`accel_verdict`): each fold fits its bias on its
training recordings' poses (as ``tune-fusion`` does) and scores the held-out recordings'
velocity increments over ACCEL_WINDOW_S, as a VIO pre-integrates them, with the bias removed
and as it came; the bias carries only if it never loses by more than LOSS_LIMIT (an IMU's
accelerometer, like its gyro, may take a new bias at each power-on).

Both compare the AOE, or the tilt error alone where the recipe does not trust the poses'
heading (:func:`~denoise_imu_ros.core.schema.judged_on`); then neither deploys nor
chooses what ruins the heading beyond the poses' drift (:func:`heading_off`).
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
import sys
from typing import Any, NamedTuple

import numpy as np

from .filters import (Filter, fit_accel_bias, FUSED, run, score as fused_score,
                      TAU_ACC_GRID_S, TILT_LABEL, VQF_DEFAULTS)
from .preintegration import (errors as increment_errors, preintegrate, reference,
                             velocity_from_positions, window_starts)
from .reports import CROSSVAL_METHODS
from ..core import jsonio
from ..core.atomic import write_text
from ..core.errors import TrainingError
from ..core.metrics import FusedErrors, score
from ..core.modelfile import sample_rate
from ..core.records import Sequence
from ..core.schema import (ACCEL_CHOICES, AS_IT_CAME, BiasTracking, Blend, InputEnvelope,
                           JUDGED, judged_on, ModelMeta, parse_meta, REST_ONLY, TRACKER_ONLY,
                           VQF_BIAS_SIGMA_INIT_DEG_S)
from ..data.load import load_sequence
from ..learn import parallel
from ..learn.checkpoint import load_model, LoadedModel
from ..learn.config import load_config, TrainConfig
from ..learn.model import correct_gyro
from ..learn.train import train
from ..pipeline import envelope, rest_bias, stages, vertical


# the rows whose output bias may be tracked: the classical pipeline's (no model) too
TRACKED = (TRACKER_ONLY, 'calibrated', 'network')
CLASSICAL = ('raw', 'rest bias', TRACKER_ONLY)  # what a practitioner runs with no training
LOSS_LIMIT = 1.1  # a learnt row deployed loses to tracker only by no more on one recording
# the network's weight against the classical pipeline's (pipeline/blend.py): the first of
# equal ones is chosen, so the network's own output wins a tie
BLEND_WEIGHTS = (1.0, 0.7, 0.5, 0.3, 0.2, 0.1)
UNBLENDED = 'network unblended'  # the network row before the blend, reported beside it
ACCEL_WINDOW_S = 1.0  # the velocity increments the accelerometer is judged on (keyframes')
BIAS_REMOVED = ACCEL_CHOICES[0]
# the candidates: VQF's biasSigmaMotion (its default 0.1 deg/s) and biasForgettingTime
# (its default 100 s), beside none; each started as certain of its 0 as its motion
# updates ever make it or at VQF's 0.5 deg/s for a raw gyro (after a model what is left
# is small, and from 0.5 deg/s a start whose accelerations are not gravity, a drone
# carried, teaches it a bias an open-loop attitude never forgets: docs/method.md; after
# the turn-on bias alone a new power-on's bias in motion may be further off its bias at
# rest, which 0.5 deg/s learns sooner); each held through rotation faster than
# HOLD_ABOVE_DEG_S or never, the held one first: where the motion never turns that fast
# the two are the same, and a tie goes to it
TRACKING_GRID = tuple(BiasTracking(sigma, forget, init, hold)
                      for sigma in (0.03, 0.05, 0.07, 0.1, 0.2) for forget in (30.0, 100.0, 300.0)
                      for init in (sigma, VQF_BIAS_SIGMA_INIT_DEG_S)
                      for hold in (rest_bias.HOLD_ABOVE_DEG_S, None))


# imu/data's filter, chosen as the tracking is: VQF's accelerometer time constant and its own
# bias estimation, each with the accelerometer as it came and less the bias fitted on the
# fold's training poses (a new power-on may bring another bias: the folds say whether it carries)
FUSION_GRID = tuple((Filter('vqf', tau, est), removed) for removed in (False, True)
                    for est in (False, True) for tau in TAU_ACC_GRID_S)
FUSED_ROWS = {m: f'{m} + VQF' for m in TRACKED}
NO_MODEL_FUSED = 'raw + VQF defaults'  # what a user runs with no model


def fusion_label(flt: Filter, removed: bool) -> str:
    """Name a filter candidate in reports (the fold's accelerometer bias is not a setting)."""
    return flt.label + (", the training poses' accelerometer bias removed" if removed else '')


def tracking_label(settings: BiasTracking | None) -> str:
    """Name a tracking candidate in reports."""
    return 'none' if settings is None else settings.describe()


# each recipe key's default: what a model file written before the key existed was made with
RECIPE_DEFAULTS = {f.name: f.default for f in dataclasses.fields(TrainConfig)
                   if f.default is not dataclasses.MISSING}

CANDIDATES = {tracking_label(t): t for t in (None, *TRACKING_GRID)}  # label -> settings
HEADING_GUARD = 2.0  # judged on the tilt: a heading this many times the rest bias's is off


def folds(recordings: list[str], k: int | None = None) -> list[list[str]]:
    """Held-out groups, round-robin over the recipe's list; None = leave one out."""
    k = len(recordings) if k is None else k
    if len(recordings) < 2:
        raise TrainingError(f'cross-recording validation needs at least two recordings in the '
                            f'recipe (it has {len(recordings)}): each fold holds one out')
    if not 2 <= k <= len(recordings):
        raise TrainingError(f'folds must be between 2 and {len(recordings)} (one per '
                            f'recording of the recipe), got {k}')
    return [recordings[i::k] for i in range(k)]


def session_folds(recordings: list[str], sessions: list[str],
                  option: str = '--sessions', what: str = 'session') -> list[list[str]]:
    """
    Held-out groups of recordings that share a power-on: ``sessions`` lists each group.

    Each group is comma-separated recording names of the recipe; every recording of the
    recipe is in exactly one, and there are at least two: a fold then trains on other
    power-ons only and scores one it never saw, as a robot's next start-up. (``option``
    and ``what`` name another grouping in the errors: :func:`motion_folds`.)
    """
    groups = [[n for n in group.split(',') if n] for group in sessions]
    listed = [n for group in groups for n in group]
    twice = sorted({n for n in listed if listed.count(n) > 1})
    unknown = sorted(set(listed) - set(recordings))
    missing = [n for n in recordings if n not in listed]
    why = (f'{", ".join(twice)} in two {what}s' if twice else
           f'{", ".join(unknown)} not in the recipe' if unknown else
           f'{", ".join(missing)} in no {what}' if missing else
           f'fewer than two {what}s' if len([g for g in groups if g]) < 2 else None)
    if why:
        raise TrainingError(f"{option}: {why} (each of the recipe's recordings in exactly "
                            'one comma-separated group, at least two groups)')
    return [g for g in groups if g]


def motion_folds(recordings: list[str], sessions: list[str], motions: list[str]
                 ) -> list[tuple[list[str], list[str]]]:
    """
    Return (held out, trained on) pairs that leave one session and one motion kind out.

    Each fold holds out the recordings of one session that are of one motion kind
    (``motions`` groups the recordings as ``sessions`` does: rotation, translation,
    disturbed...), and trains on those of the other sessions that are of the other kinds:
    the held-out recordings' power-on and motion both unseen, as a robot's next start-up
    doing something its training never showed. Every recording is held out once.
    """
    by_session = session_folds(recordings, sessions)
    by_motion = session_folds(recordings, motions, '--motions', 'motion kind')
    pairs = []
    for session in by_session:
        for motion in by_motion:
            held = [n for n in recordings if n in session and n in motion]
            train = [n for n in recordings if n not in session and n not in motion]
            if held and not train:
                raise TrainingError(f'--motions: holding out {", ".join(held)} leaves no '
                                    'recording of another session and another motion kind '
                                    'to train on')
            if held:
                pairs.append((held, train))
    return pairs


def crossval(config: str | Path, k: int | None = None, out: Path | None = None,
             progress: bool = True, only_fold: int | None = None,
             seeds: list[int] | None = None, sessions: list[str] | None = None,
             motions: list[str] | None = None, **overrides: Any) -> dict[str, Any] | None:
    """
    Train and score every fold of the recipe at ``config``; return the report.

    ``overrides`` are recipe keys (seed, steps, workers, data). With ``out``, each fold's
    two models are written to ``out/fold<i>/`` and the report to ``out/crossval.json``;
    a fold whose two models are there already, trained by this recipe, is scored without
    training again, so a stopped run resumes. ``only_fold`` trains that fold alone and
    returns None (separate processes can share the folds of one ``out``).

    ``seeds`` trains every fold once per seed (into ``out/seed<s>/fold<i>/``) and scores
    each held-out recording with the mean of the seeds' corrected gyros: the verdict of
    the ensemble ``denoise-imu ensemble`` would ship, with each seed's own figures beside
    it (``per_seed``) for the spread. The calibration row is likewise the mean of the
    seeds' calibrations.

    ``sessions`` (comma-separated recordings sharing a power-on, one string a session)
    makes the folds leave one power-on out instead of ``k`` groups of recordings; with
    ``motions`` (the same for motion kinds) each fold leaves one session's recordings of
    one motion kind out, trained on the other sessions' other kinds (:func:`motion_folds`).
    """
    if parallel.torchrun_rank() is not None:  # its other processes would have no model
        raise TrainingError('crossval does not run under torchrun: train its folds as '
                            'separate processes (--fold I, each with --workers if wanted)')
    if seeds is not None and (not seeds or len(set(seeds)) != len(seeds)
                              or not all(isinstance(s, int) for s in seeds)
                              or overrides.get('seed') is not None):
        raise TrainingError(f'--seeds must list distinct seeds (and no --seed), got {seeds}')
    if motions is not None and sessions is None:
        raise TrainingError('--motions needs --sessions: its folds leave a session and a '
                            'motion kind out')
    recipe = load_config(config, **overrides)
    runs: list[int | None] = [None] if seeds is None else list(seeds)
    raw_rows: dict[str, dict[str, dict[str, float]]] = {}
    tracked: dict[str, Any] = {}      # recording -> candidate -> row -> figures
    tracked_seed: dict[str, Any] = {}  # the same for each seed alone
    networks: dict[str, Networks] = {}  # recording -> the network's outputs, to blend
    held: dict[str, Held] = {}  # recording -> every row's ensemble output, for imu/data
    fold_of: dict[str, int] = {}
    accel: dict[str, dict[str, float]] = {}  # recording -> velocity increment error per choice
    if sessions is not None and k is not None:
        raise TrainingError('--folds and --sessions: give one (sessions are the folds)')
    pairs = (motion_folds(recipe.sequences, sessions, motions) if motions is not None else [
        (held, [s for s in recipe.sequences if s not in held]) for held in (
            folds(recipe.sequences, k) if sessions is None
            else session_folds(recipe.sequences, sessions))])
    fold_list = [held for held, _ in pairs]
    if only_fold is not None and not (out is not None and 0 <= only_fold < len(fold_list)):
        raise TrainingError(f'--fold {only_fold}: needs --out and a fold from 0 to '
                            f'{len(fold_list) - 1}')
    for i, (held_out, train_on) in enumerate(pairs):
        if only_fold is not None and i != only_fold:
            continue
        models = []
        for seed in runs:
            keys = dict(overrides, sequences=train_on, **({} if seed is None else {'seed': seed}))
            folder = None if out is None else (
                out / f'fold{i}' if seed is None else out / f'seed{seed}' / f'fold{i}')
            models.append(_fold_models(folder, load_config(config, **keys),
                                       load_config(config, **keys, calibration_only=True),
                                       f'fold {i + 1}/{len(fold_list)}'
                                       + ('' if seed is None else f', seed {seed}'), progress))
        if only_fold is not None:
            return None
        fields = {TRACKER_ONLY: 1, 'calibrated': models[0][1].config.receptive_field,
                  'network': models[0][0].config.receptive_field}
        bounds = [{TRACKER_ONLY: None, 'calibrated': calib.meta.input_envelope,
                   'network': net.meta.input_envelope} for net, calib in models]
        ensemble_bounds = {TRACKER_ONLY: None,
                           'calibrated': bounds[0]['calibrated'],  # the calibration: seed 0's
                           'network': envelope.combine([b['network'] for b in bounds])}
        field = models[0][0].model.receptive_field
        trained = [_read(recipe, name, field) for name in train_on]
        fitted = fit_accel_bias(trained)
        del trained
        for name in held_out:
            seq = _read(recipe, name, field)
            rest = rest_bias.baseline_gyro(models[0][0], seq.stream)
            raw_rows[name] = {'raw': score(seq, seq.imu[:, :3]),
                              'rest bias': score(seq, seq.on_poses(rest))}
            fed = stages.model_input(models[0][0], seq.stream)  # one recipe, one input
            gyros = [{TRACKER_ONLY: rest, 'calibrated': correct_gyro(calib.model, fed),
                      'network': correct_gyro(net.model, fed)} for net, calib in models]
            rate, drop = sample_rate(models[0][0]), vertical.drops_vertical(models[0][0].meta)
            ensemble = {m: np.mean([g[m] for g in gyros], axis=0) for m in TRACKED}
            tracked[name] = _candidates(seq, ensemble, rate, fed, ensemble_bounds, fields, drop)
            tracked_seed[name] = [_candidates(seq, g, rate, fed, b, fields, drop)
                                  for g, b in zip(gyros, bounds)] if seeds is not None else []
            networks[name] = Networks(
                seq, fed, rate, fields['network'], drop,
                [ensemble['network']] + ([g['network'] for g in gyros] if seeds else []),
                [ensemble_bounds['network']] + ([b['network'] for b in bounds] if seeds else []))
            held[name] = Held(ensemble, ensemble_bounds, fields,
                              None if fitted is None else fitted[0])
            fold_of[name] = i
            accel[name] = accel_rows(seq, ensemble['network'],
                                     None if fitted is None else fitted[0])
    key, why = judged_on(recipe.heading_weight)
    per_recording, per_seed, tracking = _nested(raw_rows, tracked, tracked_seed, fold_of,
                                                seeds or [], key)
    blend = _blend(networks, tracking, per_recording, per_seed, fold_of, seeds or [], key)
    # imu/data's filter where the validation tails cannot choose it: on another power-on
    fusion = None if sessions is None else _fusion(networks, held, tracking, blend, fold_of, key)
    report = summarize(per_recording, key)
    sizes = sorted({len(train) for _, train in pairs})
    report.update(recipe=str(config), folds=fold_list, steps=recipe.steps,
                  train_config=recipe.recipe(),
                  fold_kind='leave one session and one motion kind out' if motions else
                  'leave one power-on session out' if sessions else 'leave recordings out',
                  fold_training=(f'each fold trains on {"-".join(map(str, sizes))} of the '
                                 f"recipe's {len(recipe.sequences)} recordings; a model of "
                                 'the whole recipe trains on all of them, so these figures '
                                 'judge networks trained on less data than it'),
                  tracking=tracking, blend=blend, judged_on=key,
                  **({} if fusion is None else {'fusion': fusion}),
                  accelerometer=accel_verdict(accel),
                  **({} if why is None else {'judged_on_why': why}),
                  **({'seed': recipe.seed} if seeds is None else {
                      'seeds': runs, 'per_seed': {str(s): summarize(r, key)
                                                  for s, r in per_seed.items()}}))
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        write_text(out / 'crossval.json', jsonio.dumps(report, indent=2))
    return report


def _read(recipe: TrainConfig, name: str, min_samples: int) -> Sequence:
    """Return a recording of the recipe, read as training reads it."""
    return load_sequence(Path(recipe.data) / name, recipe.imu_topic, recipe.pose_topic,
                         recipe.max_gt_gap_s, min_samples=min_samples,
                         align_poses=recipe.align, poses=recipe.poses)


def accel_rows(seq: Sequence, gyro: np.ndarray, bias: np.ndarray | None) -> dict[str, float]:
    """
    Return the RMS velocity increment error (m/s) of ``seq`` per accelerometer choice.

    Over back-to-back ACCEL_WINDOW_S windows with ``gyro``, against the poses (their
    velocity their derivative); the accelerometer as it came and, where a fold fitted one,
    less its training recordings' ``bias``.
    """
    stamp_s = (seq.stamp_ns - seq.stamp_ns[0]) * 1e-9
    length = max(1, round(ACCEL_WINDOW_S * seq.rate_hz))
    starts = window_starts(seq.gt_valid, length)
    if not len(starts):
        return {}
    ref = reference(seq.gt_quat, seq.gt_pos, velocity_from_positions(seq.gt_pos, stamp_s),
                    stamp_s, starts, length)
    choices = {AS_IT_CAME: seq.imu[:, 3:]}
    if bias is not None:
        choices[BIAS_REMOVED] = seq.imu[:, 3:] - bias
    return {label: float(np.sqrt(np.mean(increment_errors(
        preintegrate(gyro, accel, stamp_s, starts, length), ref)['velocity_m_s'] ** 2)))
        for label, accel in choices.items()}


def accel_verdict(per_recording: dict[str, dict[str, float]]) -> dict[str, Any]:
    """
    Return whether the accelerometer's training bias carries to unseen recordings, and why.

    Removed only if it lowers the mean velocity increment error and loses on no recording
    by more than LOSS_LIMIT; a recording no fold could fit a bias for, or too short for
    one window, leaves the accelerometer as it came.
    """
    scored = {n: r for n, r in per_recording.items() if r}
    report: dict[str, Any] = {'window_s': ACCEL_WINDOW_S, 'recordings': per_recording}
    if not scored or any(BIAS_REMOVED not in r for r in scored.values()):
        return dict(report, deploy=AS_IT_CAME, verdict='no bias fitted on the training '
                    "recordings' poses for every fold: the accelerometer as it came")
    mean = {c: float(np.mean([r[c] for r in scored.values()])) for c in ACCEL_CHOICES}
    worst = max(scored, key=lambda n: scored[n][BIAS_REMOVED] / scored[n][AS_IT_CAME])
    ratio = scored[worst][BIAS_REMOVED] / scored[worst][AS_IT_CAME]
    carries = mean[BIAS_REMOVED] < mean[AS_IT_CAME] and ratio <= LOSS_LIMIT
    line = (f'velocity increments over {ACCEL_WINDOW_S:g} s, mean over {len(scored)} unseen '
            f'recordings: {mean[BIAS_REMOVED]:.3f} m/s with the training bias removed against '
            f'{mean[AS_IT_CAME]:.3f} as it came, at worst {ratio:.2f}x ({worst}): '
            + ('remove it' if carries else 'the accelerometer as it came'))
    return dict(report, mean=mean, deploy=BIAS_REMOVED if carries else AS_IT_CAME,
                verdict=line)


# recipe keys a fold and the model it judges may differ in (steps: compared apart)
NOT_THE_RECIPE = {'sequences', 'seed', 'steps', 'calibration_only'}


def attach_mismatches(report: dict[str, Any], meta: ModelMeta) -> list[str]:
    """
    Return what makes a cross-recording report not that of a model's own training.

    The folds must hold out the model's training recordings and train as long as it did,
    with its recipe: folds of a shortened recipe (``--steps``), or of another window,
    increments or rest-bias setting, judge a network that was never shipped.
    """
    why = []
    held_out = sorted(name for fold in report.get('folds', []) for name in fold)
    trained_on = sorted(meta.train_sequences)
    if trained_on and held_out != trained_on:
        why.append(f'its folds hold out {held_out}, the model was trained on {trained_on}')
    steps = meta.recipe('steps')
    if steps is not None and report.get('steps') not in (None, steps):
        why.append(f'its folds trained {report["steps"]} steps, the model {steps}')
    folds = json.loads(jsonio.dumps(report.get('train_config') or {}))
    model = meta.train_config
    differ = sorted(k for k in set(folds) & set(model) - NOT_THE_RECIPE if folds[k] != model[k])
    if differ:
        why.append(f'its folds trained another recipe (they differ in {", ".join(differ)})')
    return why


def _fold_models(folder: Path | None, cfg: Any, calib_cfg: Any, label: str,
                 progress: bool) -> tuple[LoadedModel, LoadedModel]:
    """Return a fold's network and calibration: from ``folder`` if there, else trained."""
    kept = _trained_fold(folder, cfg, calib_cfg) if folder is not None else None
    if kept is not None:
        print(f'{label}: its models are in {folder}', file=sys.stderr)
        return kept
    print(f'{label}: training on {", ".join(cfg.sequences)}', file=sys.stderr)
    net, calib = train(cfg, progress=progress), train(calib_cfg, progress=False)
    if folder is not None:
        net.save(folder / 'network.safetensors')
        calib.save(folder / 'calibrated.safetensors')
    return (LoadedModel(net.model, parse_meta(net.meta, label), Path(f'{label}, network')),
            LoadedModel(calib.model, parse_meta(calib.meta, label),
                        Path(f'{label}, calibration')))


def _candidates(seq: Any, gyros: dict[str, np.ndarray], rate_hz: float, fed: np.ndarray,
                bounds: dict[str, InputEnvelope | None], fields: dict[str, int],
                drop: bool) -> dict[str, dict[str, dict[str, float]]]:
    """
    Return each tracking candidate's figures (label -> row -> score) of untracked gyros.

    Each gyro (over the recording's whole stream, as ``fed``) tracked and guarded by its
    row's input envelope, and its correction about the vertical dropped where the recipe's
    is (``drop``; the tracker only corrects nothing to drop), as every path ends it
    (:func:`~denoise_imu_ros.pipeline.stages.finish`). A candidate held above a rate the
    gyro never reaches runs as its unheld twin: its figures are that one's, not run again.
    """
    figures: dict[str, dict[str, dict[str, float]]] = {label: {} for label in CANDIDATES}
    for m, g in gyros.items():
        reached: dict[float, bool] = {}  # hold bound -> whether this gyro turns that fast
        runs: dict[BiasTracking | None, dict[str, float]] = {}  # tracking as run -> figures
        for label, t in CANDIDATES.items():
            bound = None if t is None else t.hold_above_deg_s
            if bound is not None:
                if bound not in reached:
                    reached[bound] = bool(rest_bias.fast_rotation(g, rate_hz, bound).any())
                if not reached[bound]:
                    t = dataclasses.replace(t, hold_above_deg_s=None)
            if t not in runs:
                runs[t] = score(seq, seq.on_poses(stages.finish(
                    g, fed, rate_hz, t, bounds[m], fields[m], drop and m != TRACKER_ONLY)))
            figures[label][m] = dict(runs[t])
    return figures


def _choose(tracked: dict[str, Any], names: list[str], key: str,
            raw_rows: dict[str, Any]) -> dict[str, str]:
    """
    Return, per row, the candidate of lowest mean ``key`` figure over ``names``.

    Judged on the tilt, among the candidates whose heading is not off (the bar of
    :func:`heading_off`, over the same recordings) where any is: a tracker moves the
    bias about the vertical too, which the tilt cannot see.
    """
    def mean(label: str, m: str, k: str) -> float:
        return float(np.mean([tracked[n][label][m][k] for n in names]))
    bar = (HEADING_GUARD * np.mean([raw_rows[n]['rest bias']['aoe_yaw_deg'] for n in names])
           if key == 'tilt_deg' and all('rest bias' in raw_rows[n] for n in names) else None)
    chosen = {}
    for m in TRACKED:
        fine = [c for c in CANDIDATES if bar is None or mean(c, m, 'aoe_yaw_deg') <= bar]
        chosen[m] = min(fine or CANDIDATES, key=lambda label: mean(label, m, key))
    return chosen


def _nested(raw_rows: dict[str, Any], tracked: dict[str, Any], tracked_seed: dict[str, Any],
            fold_of: dict[str, int], seeds: list[int], key: str
            ) -> tuple[dict[str, Any], dict[int, Any], dict[str, Any]]:
    """
    Return the held-out figures, each seed's, and the report's ``tracking`` entry.

    Each fold's recordings are scored with the tracking candidate the other folds'
    recordings chose (on the ``key`` figure); the shipped models get the one all of them
    choose.
    """
    choice = {f: _choose(tracked, [n for n in tracked if fold_of[n] != f], key, raw_rows)
              for f in set(fold_of.values())}

    def rows(name: str, figures: dict[str, Any]) -> dict[str, Any]:
        return {**raw_rows[name], **{m: figures[choice[fold_of[name]][m]][m] for m in TRACKED}}
    per_recording = {name: rows(name, tracked[name]) for name in tracked}
    per_seed = {seed: {name: rows(name, tracked_seed[name][k]) for name in tracked}
                for k, seed in enumerate(seeds)}
    shipped = _choose(tracked, list(tracked), key, raw_rows)
    return per_recording, per_seed, {
        'chosen': {m: _labelled(shipped[m]) for m in TRACKED},
        'chosen_on': f"the mean {JUDGED[key]} over every held-out recording; each fold's "
                     "figures use the other folds' choice",
        'per_fold': {str(f): c for f, c in choice.items()},
        'candidates': {m: {label: float(np.mean([tracked[n][label][m][key] for n in tracked]))
                           for label in CANDIDATES} for m in TRACKED},
        'recordings': {n: {m: {label: tracked[n][label][m][key] for label in CANDIDATES}
                           for m in TRACKED} for n in tracked}}


class Networks(NamedTuple):
    """A held-out recording's network outputs, untracked: the ensemble's, then each seed's."""

    seq: Any
    fed: np.ndarray
    rate_hz: float
    field: int
    drop: bool
    gyros: list[np.ndarray]
    bounds: list[InputEnvelope | None]


def _blend(networks: dict[str, Networks], tracking: dict[str, Any],
           per_recording: dict[str, Any], per_seed: dict[int, Any], fold_of: dict[str, int],
           seeds: list[int], key: str) -> dict[str, Any]:
    """
    Blend the network rows with the classical pipeline's; return the report's ``blend``.

    Each recording's network output, tracked as its fold's figures are, is blended with
    its tracker-only row's gyro at every weight of BLEND_WEIGHTS (the classical alone
    beyond the envelope's sustained bound, :mod:`~denoise_imu_ros.pipeline.blend`). A
    fold's recordings take the weight of least mean per-recording ratio to tracker only
    over the other folds' recordings; the shipped models the weight of least over all of
    them. The ``network`` rows become the blended ones, the unblended kept beside them.
    """
    figures: dict[str, list[dict[float, Any]]] = {}  # recording -> [ensemble, seeds] -> w
    for name, n in networks.items():
        chosen = tracking['per_fold'][str(fold_of[name])]
        classical = CANDIDATES[chosen[TRACKER_ONLY]]
        figures[name] = [{w: score(n.seq, n.seq.on_poses(stages.finish(
            gyro, n.fed, n.rate_hz, CANDIDATES[chosen['network']], bounds, n.field, n.drop,
            Blend(w, classical)))) for w in BLEND_WEIGHTS}
            for gyro, bounds in zip(n.gyros, n.bounds)]

    def ratio(names: list[str], w: float) -> float:
        return float(np.mean([figures[n][0][w][key]
                              / max(per_recording[n][TRACKER_ONLY][key], 1e-9) for n in names]))

    def best(names: list[str]) -> float:
        return min(BLEND_WEIGHTS, key=lambda w: ratio(names, w))
    weight = {f: best([n for n in figures if fold_of[n] != f]) for f in set(fold_of.values())}
    for name, rows in figures.items():
        w = weight[fold_of[name]]
        per_recording[name][UNBLENDED] = per_recording[name]['network']
        per_recording[name]['network'] = rows[0][w]
        for k, seed in enumerate(seeds):
            per_seed[seed][name][UNBLENDED] = per_seed[seed][name]['network']
            per_seed[seed][name]['network'] = rows[k + 1][w]
    shipped = best(list(figures))
    return {'chosen': {'weight': shipped, 'tracking': tracking['chosen'][TRACKER_ONLY]},
            'chosen_on': 'the least mean ratio to tracker only over every held-out recording; '
                         "each fold's figures use the other folds' choice",
            'per_fold': {str(f): w for f, w in weight.items()},
            'candidates': {str(w): ratio(list(figures), w) for w in BLEND_WEIGHTS},
            'recordings': {n: {str(w): rows[0][w][key] for w in BLEND_WEIGHTS}
                           for n, rows in figures.items()}}


class Held(NamedTuple):
    """A held-out recording's untracked outputs of every tracked row (the ensemble's)."""

    gyros: dict[str, np.ndarray]
    bounds: dict[str, InputEnvelope | None]
    fields: dict[str, int]
    accel_bias: np.ndarray | None  # fitted on its fold's training poses (None: none usable)


def _fusion(networks: dict[str, Networks], held: dict[str, Held], tracking: dict[str, Any],
            blend: dict[str, Any], fold_of: dict[str, int], key: str) -> dict[str, Any]:
    """
    Choose ``imu/data``'s filter of each row on the held-out recordings; the report's ``fusion``.

    Each recording's outputs as its fold's open-loop figures have them (tracked, the
    network blended) are fed to every filter of FUSION_GRID; a fold's recordings take the
    filter of lowest mean ``key`` figure over the other folds' recordings, the shipped
    models that of all of them (the validation tails ``tune-fusion`` chooses on share the
    training's power-on and motions). Then, on the same recordings, the tilt: that
    filter's own, or VQF's defaults' on the raw IMU with that filter's heading
    (``classical_tilt``), whichever is lower. VQF's defaults on the raw gyro are scored
    beside.
    """
    figures: dict[str, dict[str, dict[str, FusedErrors]]] = {}  # recording -> row -> filter
    outs: dict[str, dict[str, np.ndarray]] = {}  # recording -> row -> output, as fed
    filters: dict[str, dict[str, Filter]] = {}   # recording -> label -> filter
    for name, h in held.items():
        n, fold = networks[name], str(fold_of[name])
        chosen = tracking['per_fold'][fold]
        mix = Blend(blend['per_fold'][fold], CANDIDATES[chosen[TRACKER_ONLY]])
        filters[name] = {fusion_label(flt, removed): dataclasses.replace(
            flt, accel_bias_m_s2=tuple(float(b) for b in h.accel_bias)) if removed else flt
            for flt, removed in FUSION_GRID if h.accel_bias is not None or not removed}
        no_model = _fused(n, VQF_DEFAULTS, n.seq.stream[:, :3])
        figures[name] = {NO_MODEL_FUSED: {NO_MODEL_FUSED: no_model}}
        outs[name] = {m: stages.finish(h.gyros[m], n.fed, n.rate_hz, CANDIDATES[chosen[m]],
                                       h.bounds[m], h.fields[m], n.drop and m != TRACKER_ONLY,
                                       mix if m == 'network' else None) for m in TRACKED}
        for m in TRACKED:
            figures[name][m] = {label: _fused(n, flt, outs[name][m])
                                for label, flt in filters[name].items()}
    split: dict[tuple[str, str, str], FusedErrors] = {}

    def classical(name: str, m: str, label: str) -> FusedErrors:  # that filter's heading
        if (name, m, label) not in split:
            flt = dataclasses.replace(filters[name][label], classical_tilt=True)
            split[name, m, label] = _fused(networks[name], flt, outs[name][m])
        return split[name, m, label]

    def mean(names: list[str], m: str, label: str, k: str, tilt: bool = False) -> float:
        return float(np.mean([getattr(classical(n, m, label) if tilt else figures[n][m][label],
                                      FUSED[k]) for n in names]))

    def best(names: list[str], m: str) -> tuple[str, bool]:  # among the filters every one has
        labels = [c for c in figures[names[0]][m] if all(c in figures[n][m] for n in names)]
        label = min(labels, key=lambda c: mean(names, m, c, key))
        return label, (mean(names, m, label, 'tilt_deg', True)
                       < mean(names, m, label, 'tilt_deg'))
    every = list(figures)
    choice = {f: {m: best([n for n in every if fold_of[n] != f], m) for m in TRACKED}
              for f in sorted(set(fold_of.values()))}
    shipped = {m: best(every, m) for m in TRACKED}

    def errors(name: str, m: str, picked: tuple[str, bool]) -> FusedErrors:
        return classical(name, m, picked[0]) if picked[1] else figures[name][m][picked[0]]

    def named(picked: tuple[str, bool]) -> str:
        return picked[0] + (TILT_LABEL if picked[1] else '')

    def cell(e: FusedErrors, label: str) -> dict[str, Any]:
        return {'aoe_deg': e.aoe, 'tilt_deg': e.tilt, 'aoe_yaw_deg': e.aoe_yaw, 'filter': label}
    recordings = {n: {NO_MODEL_FUSED: cell(figures[n][NO_MODEL_FUSED][NO_MODEL_FUSED],
                                           VQF_DEFAULTS.label),
                      **{FUSED_ROWS[m]: cell(errors(n, m, choice[fold_of[n]][m]),
                                             named(choice[fold_of[n]][m]))
                         for m in TRACKED}}
                  for n in every}
    grid = {fusion_label(flt, removed): (flt, removed) for flt, removed in FUSION_GRID}

    def stored(m: str) -> dict[str, Any]:
        flt, removed = grid[shipped[m][0]]
        std = np.sqrt(np.mean([errors(n, m, shipped[m]).std_rad ** 2 for n in every], axis=0))
        return {'label': named(shipped[m]), 'tau_acc_s': flt.tau_acc_s,
                'bias_estimation': flt.bias_estimation, 'accel_bias_removed': removed,
                'classical_tilt': shipped[m][1], 'orientation_std_rad': std.tolist()}
    return {'chosen': {m: stored(m) for m in TRACKED},
            'chosen_on': f'the mean {JUDGED[key]} over every held-out recording, then the '
                         "lower mean tilt error, the filter's own or VQF's defaults' on the "
                         "raw IMU; each fold's figures use the other folds' choice",
            'per_fold': {str(f): {m: named(p) for m, p in c.items()}
                         for f, c in choice.items()},
            'candidates': {m: {c: mean(every, m, c, key) for c in figures[every[0]][m]}
                           for m in TRACKED},
            'tilt': {m: {'own': mean(every, m, shipped[m][0], 'tilt_deg'),
                         'classical': mean(every, m, shipped[m][0], 'tilt_deg', True)}
                     for m in TRACKED},  # the mean tilt of the chosen filter, both ways
            'recordings': recordings,
            'mean': {row: {k: float(np.mean([recordings[n][row][k] for n in every]))
                           for k in ('aoe_deg', 'tilt_deg', 'aoe_yaw_deg')}
                     for row in recordings[every[0]]}}


def _fused(n: Networks, flt: Filter, gyro: np.ndarray) -> FusedErrors:
    """Return a filter's errors on a held-out recording's gyro (the raw one for its tilt)."""
    seq = n.seq
    return fused_score(seq, seq.on_poses(run(flt, gyro, seq.stream[:, 3:], n.rate_hz,
                                             seq.stream_stamp_ns, seq.stream[:, :3])))


def _labelled(label: str) -> dict[str, Any] | None:
    """Return a candidate as a model file stores it (None: no tracking)."""
    settings = CANDIDATES[label]
    return None if settings is None else dict(settings.as_dict(), label=label)


def _trained_fold(folder: Path, cfg: Any, calib_cfg: Any
                  ) -> tuple[LoadedModel, LoadedModel] | None:
    """
    Return a fold's network and calibration from ``folder`` if this recipe trained them.

    A model of another recipe (another seed, step count, increment...) is an error, not
    silently scored: the report would describe a recipe that was not run.
    """
    paths = (folder / 'network.safetensors', folder / 'calibrated.safetensors')
    if not all(p.is_file() for p in paths):
        return None
    models = []
    for path, want in zip(paths, (cfg, calib_cfg)):
        loaded = load_model(path)
        wanted = json.loads(jsonio.dumps(want.recipe()))
        # a recipe key newer than the file, at its default (the behaviour before the key
        # existed), is the recipe the file was made by
        stored = {k: v for k, v in wanted.items()
                  if v is None or k in RECIPE_DEFAULTS and RECIPE_DEFAULTS[k] == v
                  } | loaded.meta.train_config
        if stored != wanted:
            raise TrainingError(f'{path}: trained by another recipe than this fold uses '
                                '(remove it, or use another --out)')
        models.append(loaded)
    return models[0], models[1]


def summarize(per_recording: dict[str, dict[str, dict[str, float]]],
              key: str = 'aoe_deg') -> dict[str, Any]:
    """Means per method and the verdict on the ``key`` figure, per held-out recording."""
    mean = {m: {k: float(np.mean([r[m][k] for r in per_recording.values()]))
                for k in ('aoe_deg', 'aoe_yaw_deg', 'tilt_deg')} for m in CROSSVAL_METHODS
            if all(m in r for r in per_recording.values())}
    deploy, line = verdict(per_recording, mean, key)
    return {'recordings': per_recording, 'mean': mean, 'deploy': deploy, 'verdict': line}


def heading_off(mean: dict[str, dict[str, float]], key: str) -> list[str]:
    """
    Return the learnt rows a verdict on the tilt must not deploy: their heading is off.

    The tilt cannot see a heading a model or its tracking ruins. Against a VIO's poses the
    heading error of every row holds the poses' own drift, and the gyro less its turn-on
    bias learnt nothing from them: a row whose mean yaw error exceeds HEADING_GUARD times
    the rest bias's disagrees with the poses more than their drift alone explains.
    """
    if key != 'tilt_deg' or 'rest bias' not in mean:
        return []
    bar = HEADING_GUARD * mean['rest bias']['aoe_yaw_deg']
    return [m for m in ('calibrated', 'network') if m in mean and mean[m]['aoe_yaw_deg'] > bar]


def _worst_ratio(per_recording: dict[str, dict[str, dict[str, float]]], row: str,
                 bar: str, key: str) -> tuple[float, str]:
    """Return ``row``'s largest ratio to ``bar`` over the recordings, and where it is."""
    def ratio(r: dict[str, dict[str, float]]) -> float:
        return r[row][key] / r[bar][key] if r[bar][key] > 0 else (
            math.inf if r[row][key] > 0 else 1.0)
    name = max(per_recording, key=lambda n: ratio(per_recording[n]))
    return ratio(per_recording[name]), name


def _geometric_mean(per_recording: dict[str, dict[str, dict[str, float]]], row: str,
                    key: str) -> float:
    """Return ``row``'s geometric mean ``key`` over the recordings (a zero counts as 1e-9)."""
    return float(np.exp(np.mean([math.log(max(r[row][key], 1e-9))
                                 for r in per_recording.values()])))


def verdict(per_recording: dict[str, dict[str, dict[str, float]]],
            mean: dict[str, dict[str, float]], key: str = 'aoe_deg') -> tuple[str, str]:
    """
    Return what to deploy (one of DEPLOY_CHOICES), and why.

    Judged on the ``key`` figure (:func:`judged_on`), never deploying a row whose heading
    is off (:func:`heading_off`), nor a learnt row that loses to the classical pipeline
    (the gyro less its turn-on bias, its bias tracked, no model; where that row is not
    scored, the better of plain integration and the gyro less its turn-on bias)
    by more than LOSS_LIMIT on any one recording: a mean can hide many small losses. The
    network only if it beats the baseline on most recordings and on average. The baseline
    is the classical row or the calibrated IMU of lowest geometric mean over the
    recordings, each counted by its ratio, so that one recording where the tracker
    diverges does not make a rest bias that loses on most of them the bar; nor is a
    calibration that hurts new recordings (an already calibrated IMU), nor a raw gyro that
    a still start would fix. On a tie the simpler wins (recordings never still: the rest
    bias is the raw gyro).
    """
    off = heading_off(mean, key)
    order = (*CLASSICAL, 'calibrated')

    def rank(m: str) -> tuple[float, int]:
        return _geometric_mean(per_recording, m, key), order.index(m)
    classical = TRACKER_ONLY if TRACKER_ONLY in mean else min(
        (m for m in CLASSICAL if m in mean), key=rank)
    worst = {m: _worst_ratio(per_recording, m, classical, key)
             for m in ('calibrated', 'network') if m in mean}
    losing = [m for m, (ratio, _) in worst.items() if ratio > LOSS_LIMIT and m not in off]
    base = min((m for m in order if m in mean and m not in off and m not in losing), key=rank)
    label = {'calibrated': 'the calibrated IMU', 'raw': 'plain integration',
             'rest bias': 'the raw gyro less its turn-on bias',
             TRACKER_ONLY: 'the classical pipeline (the gyro less its turn-on bias, its '
                           'bias tracked, no model)'}
    names = {'calibrated': 'the calibration', 'network': 'the network'}
    yaw = ', '.join(f'{names[m]} {mean[m]["aoe_yaw_deg"]:.2f}' for m in off)
    guard = '' if not off else (
        f'{" and ".join(names[m] for m in off)} disagree{"s" if len(off) == 1 else ""} with '
        f"the poses' heading more than {HEADING_GUARD:g}x as much as the gyro less its "
        f'turn-on bias (mean yaw {yaw} against {mean["rest bias"]["aoe_yaw_deg"]:.2f} deg): '
        'not deployed; ')
    guard += ''.join(f'{names[m]} is {worst[m][0]:.2f}x {label[classical]} on '
                     f'{worst[m][1]} (more than {LOSS_LIMIT:g}x on one recording): not '
                     'deployed; ' for m in losing)
    n = len(per_recording)
    wins = sum(r['network'][key] < r[base][key] for r in per_recording.values())
    gain = (100 * (1 - mean['network'][key] / mean[base][key]) if mean[base][key] > 0
            else -math.inf if mean['network'][key] > 0 else 0.0)  # nothing beats no error
    if 'network' not in off + losing and wins > n / 2 and gain > 0:
        return 'network', (f'{guard}the network beats {label[base]} on {wins} of {n} unseen '
                           f'recordings, by {gain:.0f} % in mean {JUDGED[key]}: deploy the '
                           'network')
    deploy = {'calibrated': 'calibration', 'rest bias': REST_ONLY, 'raw': 'none',
              TRACKER_ONLY: TRACKER_ONLY}[base]
    why = ('' if 'network' in off + losing else f'the network does not beat {label[base]} '
           f'on unseen recordings ({wins} of {n}, {gain:+.0f} % in mean {JUDGED[key]}): ')
    return deploy, (f'{guard}{why}deploy '
                    + {'calibration': 'the calibration', REST_ONLY: 'no learnt correction, '
                       'only the turn-on bias removed (rest_bias)',
                       TRACKER_ONLY: 'no learnt correction: the turn-on bias removed and '
                       'the bias left tracked (tracker only)',
                       'none': 'no correction'}[deploy])
