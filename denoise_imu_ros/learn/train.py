# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Train the gyro-correcting network: ``denoise-imu train --recipe FILE``.

Read top to bottom, as nanoGPT's train.py: set-up, data, model, optimiser, helpers, then
one visible loop. The recipe (config/train_euroc.yaml) is the reference code's: every
training sequence in one batch per step, an 80 s window per sequence at a random
offset, noise augmentation, Adam with L2 weight decay and cosine warm restarts.
Validation uses the tails of the training sequences (after the training window), never
test sequences. The model kept is, per ``select``: the candidate (best-validation
checkpoint, final weights, weight average) with the lowest validation loss, the final
weights, or the weight average.
"""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass
import math
from pathlib import Path
import signal
import threading
import time
from typing import Any
import warnings

import numpy as np
import torch
import torch.distributed as dist
from tqdm import tqdm

from . import parallel
from .checkpoint import save_model
from .config import LossConfig, TrainConfig
from .loss import increment_loss
from .model import correct_gyro, GyroNet
from ..core.compat import check_stream
from ..core.errors import DataWarning, TrainingError
from ..core.limits import common_rate
from ..core.metrics import increment_residuals, increments, RESIDUAL_BLOCK, sequence_errors
from ..core.modelfile import code_version
from ..core.records import Sequence
from ..data.load import load_imu, load_sequence
from ..pipeline import envelope, rest_bias
from ..pipeline.vertical import drop_vertical, drops

RANK_SEED_STRIDE = 7919  # data-parallel process r draws its dropout masks from seed + r * this
UNUSED_INPUT_STD = 1e30  # input_std of a channel the network must not see (accel_input: false)


# ----------------------------------------------------------------------------------
# Set-up: device, process, threads

def resolve_device(device: str | None) -> str:
    """Check a ``--device`` value; None picks cuda when torch sees a GPU, else cpu."""
    if device is None:
        return 'cuda' if torch.cuda.is_available() else 'cpu'
    try:
        dev = torch.device(device)
    except (RuntimeError, TypeError) as err:
        raise TrainingError(f'device {device!r}: not a torch device (use cpu or cuda)') from err
    if dev.type == 'cuda' and not torch.cuda.is_available():
        raise TrainingError(f'device {device!r}: torch sees no CUDA GPU on this machine')
    if dev.type not in ('cpu', 'cuda'):
        raise TrainingError(f'device {device!r}: only cpu and cuda are supported')
    return str(dev)


def _setup_process(cfg: TrainConfig, rank: int) -> None:
    """Seed, share the threads, and flush denormal floats, in every process alike."""
    # the same initial weights everywhere; denormals: tiny gradients far in GELU's tail
    # made the CPU convolutions up to 50x slower
    torch.manual_seed(cfg.seed)
    torch.set_num_threads(max(1, cfg.threads // cfg.workers))
    torch.set_flush_denormal(True)


# ----------------------------------------------------------------------------------
# Data: the whole of every sequence in memory as float tensors

def load_sequences(cfg: TrainConfig) -> list[Sequence]:
    """
    Load and check the training sequences: one IMU rate, a window and a tail each.

    A sequence whose training window or validation tail holds no increment of the loss
    with trusted ground truth at every sample would train (or validate) on nothing, with
    a loss of exactly 0: that is an error naming it.
    """
    min_len = cfg.window + cfg.max_offset + 1 + 2 * cfg.loss_config().span
    receptive_field = cfg.model_config().receptive_field
    seqs = []
    for name in cfg.sequences:
        seq = load_sequence(Path(cfg.data) / name, cfg.imu_topic, cfg.pose_topic,
                            cfg.max_gt_gap_s, min_samples=max(min_len, receptive_field),
                            align_poses=cfg.align, poses=cfg.poses)
        head = cfg.window + cfg.max_offset
        for part, where in (('training window', slice(None, head + 1)),
                            ('validation tail', slice(head, None))):
            valid, length = seq.gt_valid[where], cfg.increments[0]
            pose_at = _pose_at(seq)[where] if cfg.increments_between_poses else None
            if len(increments(valid, length, pose_at)[0]) == 0:
                between = ' between poses' if cfg.increments_between_poses else ''
                raise TrainingError(
                    f'{Path(cfg.data) / name}: no {length}-sample increment{between} with '
                    f'trusted ground truth in its {part} ({100 * valid.mean():.0f} % of its '
                    'IMU stamps have trusted ground truth): nothing to supervise the loss')
        check_stream(seq.stamp_ns, seq.imu, Path(cfg.data) / name)
        seqs.append(seq)
    common_rate({s.name: s.rate_hz for s in seqs}, cfg.data)
    return seqs


def without_turn_on_bias(cfg: TrainConfig, seqs: list[Sequence]
                         ) -> tuple[list[Sequence], rest_bias.RestBiasSettings | None]:
    """
    With ``cfg.rest_bias``: every sequence's gyro less its causal turn-on bias estimate.

    The estimate starts from a prior, the mean rest bias of the training recordings that
    are ever still: a recording that starts moving (and a robot that does) is corrected
    with it until its first stillness, in training as online. The prior is measured on
    each recording's whole IMU stream, not only where it has poses: a VIO's or a SLAM's
    trajectory starts after its initialisation, and stillness outside the poses is
    still the same power-on's; and each recording's estimate runs from its first IMU
    sample (its ``lead_in`` included), as online. The bias clip (the largest distance of
    a turn-on bias from the prior, and so the slowest steady turn taken for motion) is
    VQF's 2 deg/s, or four standard deviations of the training rest biases where that is
    more (found with a wide clip). Returns the settings the model file records, None
    without ``cfg.rest_bias``.
    """
    if not cfg.rest_bias:
        return seqs, None
    rate = float(np.median([s.rate_hz for s in seqs]))
    settings = rest_bias.RestBiasSettings()
    nominal = rest_bias.nominal_bias(
        (load_imu(Path(cfg.data) / name, cfg.imu_topic).imu for name in cfg.sequences), rate,
        dataclasses.replace(settings, bias_clip_deg_s=rest_bias.WIDE_CLIP_DEG_S))
    if nominal.prior_rad_s is not None:
        clip = max(settings.bias_clip_deg_s, 4 * math.degrees(nominal.spread_rad_s))
        settings = dataclasses.replace(settings, prior_rad_s=nominal.prior_rad_s,
                                       bias_clip_deg_s=clip)
    fed = [_less(s, rest_bias.remove_rest_bias(s.stream, rate, settings)) for s in seqs]
    return fed, settings


def _less(seq: Sequence, stream: np.ndarray) -> Sequence:
    """Return ``seq`` with its IMU samples, lead-in included, replaced by ``stream``'s."""
    lead = len(seq.lead_in)
    return dataclasses.replace(seq, lead_in=stream[:lead], imu=stream[lead:])


@dataclass
class Split:
    """
    Training windows' source arrays of this process's sequences, stacked (S_mine of L).

    Shorter sequences are zero-padded at the end (padding is never drawn: valid=False).
    ``max_start`` covers every sequence, so that a data-parallel process draws what a
    one-process run draws, and keeps its own rows' draws (``mine``).
    """

    imu: torch.Tensor        # (S_mine, L, 6) float32
    dt: torch.Tensor         # (S_mine, L - 1) float64
    quat: torch.Tensor       # (S_mine, L, 4) float64
    valid: torch.Tensor      # (S_mine, L) bool
    pose_at: torch.Tensor    # (S_mine, L) bool: a pose's stamp is nearest (Sequence.pose_at)
    max_start: torch.Tensor  # (S,) int64: window starts are drawn in [0, max_start)
    mine: torch.Tensor       # (S_mine,) int64: this process's sequences, in the draws


def window_lengths(seqs: list[Sequence], cfg: TrainConfig) -> list[int]:
    """Return how many samples windows may be drawn from, per sequence: its head, or all."""
    head = cfg.window + cfg.max_offset  # the window may end at sample head - 1
    return [len(s) if cfg.whole_sequences else head for s in seqs]


def training_split(seqs: list[Sequence], cfg: TrainConfig, rank: int | None = None) -> Split:
    """
    Stack the samples windows may be drawn from: the head of each sequence, or all.

    ``rank``: the data-parallel process whose sequences are held (None: every one).
    """
    lengths = window_lengths(seqs, cfg)
    mine = (torch.arange(len(seqs)) if rank is None
            else torch.arange(rank, len(seqs), cfg.workers))
    held = [seqs[i] for i in mine.tolist()]
    held_lengths = [lengths[i] for i in mine.tolist()]
    n = max(held_lengths)

    def stack(arrays: list[np.ndarray], length: int) -> np.ndarray:
        out = np.zeros((len(arrays), length) + arrays[0].shape[1:], arrays[0].dtype)
        for row, a in zip(out, arrays):
            row[:min(len(a), length)] = a[:length]
        return out

    return Split(
        imu=torch.tensor(stack([s.imu for s in held], n), dtype=torch.float32),
        dt=torch.tensor(stack([s.dt for s in held], n - 1)),
        quat=torch.tensor(stack([s.gt_quat for s in held], n)),
        valid=torch.tensor(stack([s.gt_valid[:m] for s, m in zip(held, held_lengths)], n)),
        pose_at=torch.tensor(stack([_pose_at(s) for s in held], n)),
        max_start=torch.tensor([m - cfg.window for m in lengths]), mine=mine)


def batch(split: Split, cfg: TrainConfig, gen: torch.Generator) -> tuple[torch.Tensor, ...]:
    """
    Draw this process's windows, one per sequence at a random offset, with noise and bias.

    Returns the input, the time steps, the poses, their validity, where poses were stamped
    and the gyro bias each window was given (S, 1, 3).

    The draws are made for every sequence, in one order, whatever the process count:
    the batch of a data-parallel run is that of a one-process run.
    """
    s, w = len(split.max_start), cfg.window
    n0 = (torch.rand(s, generator=gen, dtype=torch.float64) * split.max_start).long()
    noise_std = torch.tensor([cfg.gyro_noise] * 3 + [cfg.accel_noise] * 3)
    bias_max = torch.tensor([cfg.gyro_bias] * 3 + [cfg.accel_bias] * 3)
    bias = (2 * torch.rand(s, 1, 6, generator=gen) - 1) * bias_max
    noise = noise_std * torch.randn((s, w, 6), generator=gen)
    mine = split.mine
    idx = n0[mine, None] + torch.arange(w + 1)[None]              # (S_mine, W + 1)
    rows = torch.arange(len(mine))[:, None]
    u = split.imu[rows, idx[:, :-1]] + noise[mine] + bias[mine]    # (S_mine, W, 6)
    return (u, split.dt[rows, idx[:, :-1]], split.quat[rows, idx], split.valid[rows, idx],
            split.pose_at[rows, idx], bias[mine, :, :3])


def batch_loss(model: GyroNet, drawn: tuple[torch.Tensor, ...], cfg: TrainConfig,
               offsets: torch.Tensor | None, mine: torch.Tensor) -> torch.Tensor:
    """Return the loss of one batch from ``batch``; ``offsets``: the recordings' own biases."""
    u, dt, quat, valid, pose_at, bias = (x.to(cfg.device) for x in drawn)
    omega = model(u)
    if cfg.gyro_bias_kept:  # the offset passes through: the output tracker's to remove
        omega = omega - bias
    if offsets is not None:  # each window's recording adds its own constant
        omega = omega + model.gyro_std * offsets[mine, None, :]
    return increment_loss(omega, dt, quat, valid, cfg.loss_config(),
                          parallel.sum_over_processes, pose_at)


def _pose_at(seq: Sequence) -> np.ndarray:
    """Return where a pose's stamp is nearest (none known: nowhere)."""
    return np.zeros(len(seq), bool) if seq.pose_at is None else seq.pose_at


# ----------------------------------------------------------------------------------
# Model: normalised on every training window; this process's share of the data

def build_model(cfg: TrainConfig, seqs: list[Sequence],
                rank: int) -> tuple[GyroNet, Split, torch.Generator]:
    """Return the network, the training split with this process's rows, its generator."""
    model = GyroNet(cfg.model_config())
    model.fuse_layers = cfg.fused
    split = training_split(seqs, cfg, rank)
    # every sequence's samples windows are drawn from (not the padding of shorter ones)
    flat = torch.tensor(np.concatenate([s.imu[:m] for s, m in
                                        zip(seqs, window_lengths(seqs, cfg))]),
                        dtype=torch.float32)
    std = flat.std(0, unbiased=False)
    if not cfg.accel_input:  # normalised to ~1e-30 of a unit: no weight can use them
        std[3:] = UNUSED_INPUT_STD
    model.set_normalization(flat.mean(0), std)
    if cfg.recording_bias:  # the recordings' own biases (_run) hold every constant
        constant = model.bias if cfg.calibration_only else model.net[-1].bias
        with torch.no_grad():
            constant.zero_()
        constant.requires_grad_(False)
    model.to(cfg.device)
    if cfg.workers > 1:
        parallel.sync_batch_norm(model)
        torch.manual_seed(cfg.seed + RANK_SEED_STRIDE * rank)  # its own dropout masks
    return model, split, torch.Generator().manual_seed(cfg.seed)


# ----------------------------------------------------------------------------------
# Optimiser: Adam with L2 weight decay, cosine warm restarts, optional weight average

def build_optimiser(cfg: TrainConfig, model: GyroNet,
                    offsets: torch.Tensor | None = None) -> tuple[Any, Any, Any]:
    """
    Return the optimiser, its schedule and the weight average (None without SWA).

    ``offsets``, the recordings' own biases, are optimised beside the model without weight
    decay: nothing pulls a recording's constant towards the model's.
    """
    groups = [{'params': list(model.parameters())}]
    if offsets is not None:
        groups.append({'params': [offsets], 'weight_decay': 0.0})
    optimizer = torch.optim.Adam(groups, lr=cfg.lr, weight_decay=cfg.weight_decay)
    scheduler = torch.optim.lr_scheduler.CosineAnnealingWarmRestarts(
        optimizer, T_0=cfg.restart_period, T_mult=cfg.restart_mult, eta_min=cfg.lr_min)
    swa = torch.optim.swa_utils.AveragedModel(model) if cfg.swa_start > 0 else None
    return optimizer, scheduler, swa


# ----------------------------------------------------------------------------------
# Helpers: validation on the tails of the training sequences, selection, the result

@torch.no_grad()
def validate(model: GyroNet, seqs: list[Sequence], start: int,
             loss_cfg: LossConfig, drop: bool = False) -> dict[str, Any]:
    """
    Loss, AOE and gyro residual on samples >= start; the network sees the whole past.

    Feeding the whole IMU stream (not the tail alone, and the samples before the poses
    start too) gives the tail's outputs their real causal context, as the online node
    has. With ``drop`` (a heading-less model fed the gyro less its turn-on bias) the AOE
    and the residual are of its output as every path ends it, less its correction about
    the vertical (:func:`~denoise_imu_ros.pipeline.vertical.drop_vertical`); the loss never
    sees that.
    """
    was_training = model.training
    model.eval()
    losses, aoes, residuals = [], {}, []
    tail_cfg = dataclasses.replace(loss_cfg, skip_blocks=0)
    device = next(model.parameters()).device
    for s in seqs:
        imu = torch.tensor(s.stream, dtype=torch.float32, device=device)
        omega = model(imu[None])[0].double().cpu()
        if not torch.isfinite(omega).all():
            raise TrainingError(f'{s.name}: the network gives non-finite rates on its '
                                'validation tail: the training diverged (lower the learning '
                                'rate)')
        n = (len(s) - 1 - start) // loss_cfg.span * loss_cfg.span
        sl = slice(start, start + n)
        losses.append(float(increment_loss(
            s.on_poses(omega)[None, sl], torch.tensor(s.dt[sl])[None],
            torch.tensor(s.gt_quat[start:start + n + 1])[None],
            torch.tensor(s.gt_valid[start:start + n + 1])[None], tail_cfg,
            pose_at=torch.tensor(_pose_at(s)[start:start + n + 1])[None])))
        w = s.on_poses(drop_vertical(omega.numpy(), s.stream, s.rate_hz) if drop
                       else omega.numpy())[start:]
        aoes[s.name] = sequence_errors(s.tail(start), w, distances=())[1].aoe
        # the gyro's error as the loss sees the poses: between their stamps where it does
        pose_at, length = ((_pose_at(s)[start:], loss_cfg.increments[0])
                           if loss_cfg.between_poses else (None, RESIDUAL_BLOCK))
        res, duration = increment_residuals(s.gt_quat[start:], s.gt_valid[start:], w,
                                            s.dt[start:], length, pose_at=pose_at)
        # the mean rate error over each increment, whose std a white error's shrinks by
        # the square root of its samples: that undone, a per-sample std (rad/s)
        residuals.append(res / duration[:, None] * np.sqrt(duration * s.rate_hz)[:, None])
    model.train(was_training)
    res = np.concatenate(residuals)
    return {'loss': float(np.mean(losses)), 'aoe_deg': aoes,
            'aoe_mean_deg': float(np.mean(list(aoes.values()))),
            # per-sample gyro error std (rad/s) if the error were white
            'gyro_residual_std': res.std(axis=0).tolist()}


def select(candidates: dict[str, dict[str, Any]], rule: str) -> str:
    """Name of the candidate ``rule`` keeps: best_validation (lowest loss), final or swa."""
    if rule == 'best_validation':
        return min(candidates, key=lambda name: candidates[name]['loss'])
    return rule


@dataclass
class TrainResult:
    """The selected model, its metadata, and every candidate the run produced."""

    model: GyroNet                                # eval mode, on the CPU
    meta: dict[str, Any]                          # what its model file records
    candidates: dict[str, tuple[GyroNet, dict[str, Any]]]  # name -> (model, figures)
    envelopes: dict[str, dict[str, Any]]          # name -> its input envelope

    def save(self, path: str | Path, candidates_dir: str | Path | None = None) -> None:
        """Write the chosen model, and with ``candidates_dir`` every candidate beside it."""
        save_model(path, self.model, self.meta)
        if candidates_dir is None:
            return
        for name, (model, figures) in self.candidates.items():
            save_model(Path(candidates_dir) / f'{name}.safetensors', model,
                       dict(self.meta, selected=name, validation=figures,
                            input_envelope=self.envelopes[name]))


def _envelope(model: GyroNet, seqs: list[Sequence], cfg: TrainConfig,
              rest: rest_bias.RestBiasSettings | None) -> dict[str, Any]:
    """Return the motion trained on, beyond which the runtime does not trust the model."""
    fed = [s.imu[:m] for s, m in zip(seqs, window_lengths(seqs, cfg))]
    corrections = None if rest is not None else [  # the turn-on bias is left to the model
        correct_gyro(model, imu) - imu[:, :3] for imu in fed]
    held = envelope.sustained_bound((s.imu for s in seqs), float(np.median(
        [s.rate_hz for s in seqs])))
    return envelope.measure(fed, corrections, held).as_dict()


def _finish(cfg: TrainConfig, seqs: list[Sequence], candidates: dict[str, dict[str, Any]],
            history: list[dict[str, Any]], t_start: float,
            rest: rest_bias.RestBiasSettings | None,
            recording_bias: dict[str, list[float]] | None) -> TrainResult:
    """Rebuild every candidate as a plain eval-mode network; select one; its metadata."""
    models = {}
    for name, figures in candidates.items():
        models[name] = GyroNet(cfg.model_config())  # plain BatchNorm, whatever trained it
        models[name].load_state_dict({k: v.cpu() for k, v in figures.pop('state').items()})
        models[name].eval()
    chosen = select(candidates, cfg.select)
    envelopes = {name: _envelope(m, seqs, cfg, rest) for name, m in models.items()}
    meta = {
        'dataset': cfg.dataset,
        'sample_rate_hz': float(np.median([s.rate_hz for s in seqs])),
        'train_sequences': cfg.sequences,
        'train_config': cfg.recipe(),
        'rest_bias': None if rest is None else rest.to_dict(),
        'recording_bias_rad_s': recording_bias,
        'input_envelope': envelopes[chosen],
        'pose_alignment': {s.name: s.pose_alignment for s in seqs
                           if s.pose_alignment is not None},
        'run': cfg.run_environment(),
        'selected': chosen,
        'validation': candidates[chosen],
        'candidates': candidates,
        'history': history,
        'train_seconds': time.monotonic() - t_start,
        'code_version': code_version(),
        'created': time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime()),
    }
    return TrainResult(models[chosen], meta,
                       {name: (m, candidates[name]) for name, m in models.items()}, envelopes)


# ----------------------------------------------------------------------------------
# The run: processes, then one loop

def train(cfg: TrainConfig, progress: bool = True) -> TrainResult | None:
    """
    Train per ``cfg``; return the selected model, its metadata and the candidates.

    With ``cfg.workers`` > 1 the batch is shared by that many processes (see parallel.py);
    this process is the first of them and the only one that validates and reports.
    Started by torchrun, this process is one of torchrun's (their number replaces
    ``workers``): the first returns the result, the others None.
    """
    cfg = dataclasses.replace(cfg, device=resolve_device(cfg.device))
    if parallel.torchrun_rank() is not None:
        return _run_torchrun(cfg, progress)
    if cfg.device != 'cpu':
        cfg.workers = 1  # one GPU process holds the whole batch
    seqs = load_sequences(cfg)  # here, so that bad input fails before any process starts
    if cfg.workers == 1:
        return _run(cfg, 0, seqs, progress)
    store = parallel.serve(cfg.workers)
    workers = [parallel.spawn(_worker, (cfg, rank, store.port))
               for rank in range(1, cfg.workers)]
    try:
        parallel.join(0, cfg.workers, store)
        return _run(cfg, 0, seqs, progress)
    except KeyboardInterrupt:  # Ctrl-C: the workers, which ignore it, go at once
        for proc in workers:
            proc.terminate()
        raise
    except RuntimeError as err:  # the process group broke: was it a worker?
        for proc in workers:
            proc.join(timeout=10)
        failed = [proc.exitcode for proc in workers if proc.exitcode]
        if failed:
            raise TrainingError(f'a training worker process failed (exit code {failed[0]}); '
                                'its error is printed above') from err
        raise
    finally:
        if dist.is_initialized():
            dist.destroy_process_group()
        for proc in workers:
            proc.join(timeout=10)
            if proc.is_alive():  # this process failed: nobody will talk to it any more
                proc.terminate()


def _run_torchrun(cfg: TrainConfig, progress: bool) -> TrainResult | None:
    """Train as one of torchrun's processes: CPU, the batch shared by all of them."""
    if cfg.device != 'cpu':
        raise TrainingError('under torchrun, training runs on CPU processes (--device cpu)')
    seqs = load_sequences(cfg)
    rank, world = parallel.join_torchrun()
    try:
        if world > len(seqs):  # every process says so, before any collective call
            raise TrainingError(f'torchrun started {world} processes for {len(seqs)} '
                                'training sequences: each process needs one (use '
                                f'--nproc-per-node {len(seqs)} or fewer)')
        return _run(dataclasses.replace(cfg, workers=world), rank, seqs,
                    progress and rank == 0)
    finally:
        dist.destroy_process_group()


def _worker(cfg: TrainConfig, rank: int, port: int) -> None:
    """Entry point of the data-parallel processes other than the first."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the first process's to handle
    # tqdm's default lock is a multiprocessing semaphore: terminated with this process on
    # Ctrl-C, it would be reported leaked at exit; this process shows no progress bar
    tqdm.set_lock(threading.RLock())
    # what the recordings' reading warns of, the first process has said once already
    warnings.filterwarnings('ignore', category=DataWarning)
    parallel.join(rank, cfg.workers, port)
    try:
        _run(cfg, rank, load_sequences(cfg), False)
    finally:
        dist.destroy_process_group()


def _run(cfg: TrainConfig, rank: int, seqs: list[Sequence],
         progress: bool) -> TrainResult | None:
    """Train as process ``rank`` of ``cfg.workers``; the first one returns the result."""
    t_start = time.monotonic()
    _setup_process(cfg, rank)
    seqs, rest = without_turn_on_bias(cfg, seqs)
    drop = drops(cfg.heading_weight, rest is not None)  # as the model file will say
    model, split, gen = build_model(cfg, seqs, rank)
    # each recording's own constant bias, in units of gyro_std (recording_bias)
    offsets = (torch.zeros(len(seqs), 3, device=cfg.device, requires_grad=True)
               if cfg.recording_bias else None)
    optimizer, scheduler, swa = build_optimiser(cfg, model, offsets)
    learnt = list(model.parameters()) + ([] if offsets is None else [offsets])
    loss_cfg = cfg.loss_config()
    val_start = cfg.window + cfg.max_offset

    # the loop (step 0 only validates the untrained network)
    best: dict[str, Any] = {'loss': math.inf}
    history = []
    loss = torch.tensor(0.0)
    bar = tqdm(range(0, cfg.steps + 1), disable=not progress, desc='train', unit='step')
    for step in bar:
        if step > 0:
            loss = batch_loss(model, batch(split, cfg, gen), cfg, offsets, split.mine)
            optimizer.zero_grad(set_to_none=True)
            loss.backward()
            if cfg.workers > 1:
                loss = parallel.all_reduce_grads(learnt, loss)
            if not torch.isfinite(loss):
                raise TrainingError(f'non-finite training loss at step {step} (lr '
                                    f'{scheduler.get_last_lr()[0]:.3g}); lower the learning '
                                    'rate or check the data')
            optimizer.step()
            scheduler.step()
            bar.set_postfix(loss=f'{loss.item():.4g}')
            if swa is not None and step >= cfg.swa_start:
                swa.update_parameters(model)
        if rank == 0 and (step % cfg.val_every == 0 or step == cfg.steps):
            val = validate(model, seqs, val_start, loss_cfg, drop)
            history.append({'step': step, 'train_loss': loss.item() if step else None,
                            'val_loss': val['loss'],
                            'val_aoe_mean_deg': val['aoe_mean_deg']})
            trained = f'{loss.item():.4g}' if step else '-'  # step 0: the untrained network
            bar.write(f'step {step}: train {trained}  val {val["loss"]:.4g}  '
                      f'val AOE {val["aoe_mean_deg"]:.3f} deg')
            if step > 0 and val['loss'] < best['loss']:
                best = dict(val, step=step, state=copy.deepcopy(model.state_dict()))
    if swa is not None:
        # BatchNorm statistics of the averaged weights: recomputed on training windows.
        torch.optim.swa_utils.update_bn(
            [batch(split, cfg, gen)[0].to(cfg.device) for _ in range(8)], swa)
    if rank > 0:
        parallel.leave_together()
        return None

    # candidates: the loop validated the final weights at its last step
    candidates = {'best_checkpoint': best,
                  'final': dict(val, step=cfg.steps, state=copy.deepcopy(model.state_dict()))}
    if swa is not None:
        val = validate(swa.module, seqs, val_start, loss_cfg, drop)
        candidates['swa'] = dict(val, step=cfg.steps, state=swa.module.state_dict())
        bar.write(f'SWA from step {cfg.swa_start}: val {val["loss"]:.4g}  '
                  f'val AOE {val["aoe_mean_deg"]:.3f} deg')
    recording_bias = None if offsets is None else {  # rad/s, as the last step left them
        s.name: (model.gyro_std.cpu() * b).tolist() for s, b in zip(seqs, offsets.detach().cpu())}
    result = _finish(cfg, seqs, candidates, history, t_start, rest, recording_bias)
    parallel.leave_together()
    return result
