# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Data-parallel training on one CPU: processes that share a batch and one set of weights.

One process with two threads runs a EuRoC training step in 0.53 s, two single-threaded
processes that each take half of the sequences in 0.45 s (bench/train_speed.py). This
module keeps the split exact, so that it changes speed only:
  - BatchNorm statistics and their gradients are summed over processes (``SyncBatchNorm``),
    so every process normalises with the statistics of the whole batch;
  - the loss divides by the whole batch's block count (``increment_loss(reduce_count=...)``)
    and gradients are summed (``all_reduce_grads``), giving the whole batch's gradient;
  - every process then takes the same optimiser step, so the weights stay identical;
  - every process draws the whole batch's window offsets, noise and biases from the
    seed, as one process would, and keeps its own sequences' (``train.batch``).
Only dropout masks differ from a one-process run (they are random either way).
The processes are started here (``--workers``), or by ``torchrun``, PyTorch's own
launcher, whose standard environment (``RANK``, ``WORLD_SIZE``, ``MASTER_ADDR``, ...)
makes them one group across machines.
"""

from __future__ import annotations

from collections.abc import Callable
import datetime
import multiprocessing
import os
from typing import Any

import torch
from torch import nn
import torch.distributed as dist
import torch.nn.functional as F  # noqa: N812

HOST = '127.0.0.1'
# rank 0 validates, and at the end chooses and writes the model, while the others wait
TIMEOUT = datetime.timedelta(minutes=10)


def serve(world: int) -> dist.TCPStore:
    """Open the rendezvous of ``world`` processes on a free localhost port (first process)."""
    return dist.TCPStore(HOST, 0, world, is_master=True, timeout=TIMEOUT,
                         wait_for_workers=False)


def join(rank: int, world: int, store: dist.TCPStore | int) -> None:
    """Join the process group through ``store`` (first process) or its port (the others)."""
    os.environ.setdefault('GLOO_SOCKET_IFNAME', 'lo')  # localhost only, whatever the NICs
    if isinstance(store, int):
        store = dist.TCPStore(HOST, store, world, is_master=False, timeout=TIMEOUT)
    dist.init_process_group('gloo', store=store, rank=rank, world_size=world,
                            timeout=TIMEOUT)


def torchrun_rank() -> int | None:
    """Return this process's rank when torchrun (or its env:// protocol) started it."""
    env = os.environ
    if 'TORCHELASTIC_RUN_ID' in env or all(k in env for k in ('RANK', 'WORLD_SIZE',
                                                              'MASTER_ADDR')):
        return int(env.get('RANK', '0'))
    return None


def join_torchrun() -> tuple[int, int]:
    """Join torchrun's group through its environment (env:// rendezvous); rank, world."""
    dist.init_process_group('gloo', init_method='env://', timeout=TIMEOUT)
    return dist.get_rank(), dist.get_world_size()


def leave_together() -> None:
    """
    Wait until every process is done, so that they leave the group at once.

    A process that leaves while another still works (the first one validates and writes
    after the last collective step) has been seen aborting at exit under torchrun.
    """
    if dist.is_initialized():
        dist.barrier()


def spawn(target: Callable[..., None], args: tuple[Any, ...]) -> multiprocessing.Process:
    """Start ``target(*args)`` in a fresh interpreter (fork would copy torch's threads)."""
    proc = multiprocessing.get_context('spawn').Process(target=target, args=args, daemon=True)
    proc.start()
    return proc


def sum_over_processes(t: torch.Tensor) -> torch.Tensor:
    """Sum of ``t`` over all processes (``t`` itself when not data-parallel)."""
    if not dist.is_initialized():
        return t
    t = t.clone()
    dist.all_reduce(t)
    return t


def all_reduce_grads(params: list[nn.Parameter], loss: torch.Tensor) -> torch.Tensor:
    """Sum gradients and the loss over processes in one message; return the total loss."""
    grads = [p.grad for p in params if p.grad is not None]
    flat = torch.cat([g.reshape(-1).double() for g in grads] + [loss.detach().reshape(1)])
    flat = sum_over_processes(flat)
    offset = 0
    for g in grads:
        g.copy_(flat[offset:offset + g.numel()].view_as(g))
        offset += g.numel()
    return flat[-1]


class _SyncBatchNormFn(torch.autograd.Function):
    """Training-mode batch norm over (B, C, T) whose statistics span every process."""

    @staticmethod
    def forward(ctx: Any, x: torch.Tensor, weight: torch.Tensor, bias: torch.Tensor,
                eps: float) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Return the output, the batch mean and the unbiased batch variance."""
        # BatchNorm's own per-channel kernel: ~5x faster here than torch.var_mean
        mean, var = torch.batch_norm_update_stats(x, None, None, 0.0)  # var: biased
        n = x.shape[0] * x.shape[2]
        mean64 = mean.double()
        # per-channel sums of x and x^2, and the count, in float64: the cancellation in
        # E[x^2] - mean^2 below then costs nothing at float32 precision
        local = torch.cat([n * mean64, n * (var.double() + mean64 ** 2),
                           torch.tensor([float(n)], dtype=torch.float64)])
        total = sum_over_processes(local)
        c, count = x.shape[1], total[-1]
        mean64 = total[:c] / count
        var64 = (total[c:2 * c] / count - mean64 ** 2).clamp(min=0)
        mean, var = mean64.float(), var64.float()
        ctx.save_for_backward(x, weight, mean, var)
        ctx.eps, ctx.count = eps, float(count)
        y = F.batch_norm(x, mean, var, weight, bias, training=False, eps=eps)
        unbiased = (var64 * count / (count - 1)).float()  # what BatchNorm keeps running
        ctx.mark_non_differentiable(mean, unbiased)
        return y, mean, unbiased

    @staticmethod
    def backward(ctx: Any, grad: torch.Tensor, *_: Any) -> tuple[Any, ...]:
        """Gradients of x, weight and bias (the latter two this process's share)."""
        x, weight, mean, var = ctx.saved_tensors
        # Eval-mode backward with the batch statistics: grad * weight * invstd, and the
        # local sums of grad * x_hat and grad (the weight and bias gradients) in one pass.
        gx, gw, gb = torch.ops.aten.native_batch_norm_backward(
            grad.contiguous(), x, weight, mean, var, None, None, False, ctx.eps,
            [True, True, True])
        sums = sum_over_processes(torch.cat([gw, gb]))
        gw_all, gb_all = sums.chunk(2)
        # The statistics depend on x: subtract their share, using the whole batch's sums.
        invstd = torch.rsqrt(var + ctx.eps)
        scale = weight * invstd / ctx.count
        slope = -scale * invstd * gw_all                       # per channel, times x
        offset = -scale * gb_all - slope * mean                # per channel
        gx.addcmul_(x, slope[:, None]).add_(offset[:, None])
        return gx, gw, gb, None


class SyncBatchNorm(nn.BatchNorm1d):
    """``nn.BatchNorm1d`` whose training statistics span all data-parallel processes."""

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """Normalise; in training mode update the running statistics like BatchNorm1d."""
        if not self.training:
            return super().forward(x)
        y, mean, var = _SyncBatchNormFn.apply(x, self.weight, self.bias, self.eps)
        update_running_stats(self, mean, var)
        return y


@torch.no_grad()
def update_running_stats(norm: nn.BatchNorm1d, mean: torch.Tensor, var: torch.Tensor) -> None:
    """Move a BatchNorm's running statistics towards a batch's, as BatchNorm1d does."""
    norm.num_batches_tracked += 1
    # momentum None = cumulative average (what swa_utils.update_bn asks for)
    factor = 1.0 / float(norm.num_batches_tracked) if norm.momentum is None else norm.momentum
    norm.running_mean.lerp_(mean, factor)
    norm.running_var.lerp_(var, factor)


def sync_batch_norm(model: nn.Module) -> nn.Module:
    """Replace every BatchNorm1d of ``model`` by a SyncBatchNorm holding the same state."""
    for name, child in model.named_children():
        if isinstance(child, nn.BatchNorm1d) and not isinstance(child, SyncBatchNorm):
            synced = SyncBatchNorm(child.num_features, child.eps, child.momentum)
            synced.load_state_dict(child.state_dict())
            setattr(model, name, synced)
        else:
            sync_batch_norm(child)
    return model
