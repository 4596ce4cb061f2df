# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Data-parallel training gives the one-process gradient; a 2-process run trains."""

from pathlib import Path

from denoise_imu_ros.core.architecture import ModelConfig
from denoise_imu_ros.core.errors import TrainingError
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.learn import parallel
from denoise_imu_ros.learn import train as train_module
from denoise_imu_ros.learn.config import load_config
from denoise_imu_ros.learn.loss import increment_loss, LossConfig
from denoise_imu_ros.learn.model import GyroNet
from denoise_imu_ros.learn.train import train
from helpers import ROOT
import numpy as np
import pytest
import torch
import torch.distributed as dist

CONFIG = ROOT / 'config' / 'train_euroc.yaml'
SEQUENCES = ['MH_01_easy', 'V1_02_medium', 'V2_01_easy']
N = 2048


@pytest.fixture(scope='module')
def short_euroc(euroc, tmp_path_factory) -> Path:
    """Return the sequences' first 15 s: N samples and a validation tail after them."""
    from helpers import crop_asl
    folder = tmp_path_factory.mktemp('euroc')
    for name in SEQUENCES:
        crop_asl(euroc / name, folder / name, 15.0)
    return folder


def _gradients(rank: int, world: int, store, data: Path, out: Path) -> None:
    """Loss, gradients and BatchNorm statistics of one step, as process rank of world."""
    if world > 1:
        parallel.join(rank, world, store)
    torch.set_num_threads(1)
    seqs = [load_sequence(data / name) for name in SEQUENCES]
    u = torch.tensor(np.stack([s.imu[:N] for s in seqs]), dtype=torch.float32)
    dt = torch.tensor(np.stack([s.dt[:N] for s in seqs]))
    quat = torch.tensor(np.stack([s.gt_quat[:N + 1] for s in seqs]))
    valid = torch.tensor(np.stack([s.gt_valid[:N + 1] for s in seqs]))
    valid[0, 300:900] = False  # uneven counts of valid blocks between the processes
    rows = slice(rank, None, world)  # process 0: sequences 0 and 2, process 1: sequence 1
    for fused in (True, False):  # learn/fused.py or PyTorch's layers
        torch.manual_seed(0)
        model = GyroNet(ModelConfig(dropout=0.0))
        model.fuse_layers = fused
        model.set_normalization(u.reshape(-1, 6).mean(0), u.reshape(-1, 6).std(0))
        if world > 1:
            parallel.sync_batch_norm(model)
        loss = increment_loss(model(u[rows]), dt[rows], quat[rows], valid[rows], LossConfig(),
                              parallel.sum_over_processes)
        loss.backward()
        if world > 1:
            loss = parallel.all_reduce_grads(list(model.parameters()), loss)
        arrays = {f'grad.{k}': p.grad.numpy() for k, p in model.named_parameters()}
        arrays.update({f'state.{k}': v.numpy() for k, v in model.state_dict().items()})
        np.savez(out / f'{world}_{rank}_{fused}.npz', loss=loss.item(), **arrays)
    if world > 1:
        dist.destroy_process_group()


def test_two_processes_give_the_whole_batch_gradient_and_statistics(short_euroc, tmp_path):
    """With the fused layers and with PyTorch's, one spawn for both."""
    _gradients(0, 1, None, short_euroc, tmp_path)
    store = parallel.serve(2)
    other = parallel.spawn(_gradients, (1, 2, store.port, short_euroc, tmp_path))
    _gradients(0, 2, store, short_euroc, tmp_path)
    other.join(timeout=60)
    assert other.exitcode == 0
    for fused in (True, False):
        one = np.load(tmp_path / f'1_0_{fused}.npz')
        first, second = (np.load(tmp_path / f'2_{r}_{fused}.npz') for r in (0, 1))
        assert float(first['loss']) == float(second['loss'])
        np.testing.assert_allclose(first['loss'], one['loss'], rtol=1e-6)
        # (the biases of convolutions followed by BatchNorm have gradients that are rounding
        # noise: tolerances are relative to the largest gradient)
        scale = max(np.abs(one[k]).max() for k in one.files if k.startswith('grad.'))
        for key in one.files:
            if key.startswith(('grad.', 'state.')):
                np.testing.assert_array_equal(first[key], second[key])  # processes agree
                atol = 1e-5 * (scale if key.startswith('grad.') else np.abs(one[key]).max())
                np.testing.assert_allclose(first[key], one[key], rtol=1e-4, atol=atol,
                                           err_msg=f'{key}, fused {fused}')
        assert any(np.abs(one[k]).max() > 0 for k in one.files if k.startswith('grad.net.0'))


def test_a_two_process_run_trains_and_returns_a_plain_model(short_euroc):
    cfg = load_config(CONFIG, data=str(short_euroc), sequences=SEQUENCES[:2], window=N,
                      steps=12, val_every=6, restart_period=12, swa_start=6, workers=2)
    result = train(cfg, progress=False)
    model, meta = result.model, result.meta
    history = meta['history']
    assert history[-1]['val_loss'] < 0.5 * history[0]['val_loss']
    assert not any(isinstance(m, parallel.SyncBatchNorm) for m in model.modules())
    assert not dist.is_initialized()
    assert meta['run']['workers'] == 2 and 'workers' not in meta['train_config']


@pytest.fixture(scope='module')
def built_in(tmp_path_factory) -> Path:
    """Train `--workers 2` on two synthetic recordings (the train command, in this process)."""
    import yaml
    from denoise_imu_ros.cli import main
    from helpers import write_asl
    folder = tmp_path_factory.mktemp('built_in')
    for i in range(2):
        write_asl(folder / f'rec{i}', n_imu=2400, yaw_rate=0.2 + 0.1 * i, gyro_bias=0.01)
    recipe = yaml.safe_load(CONFIG.read_text())
    recipe.update(data=str(folder), sequences=['rec0', 'rec1'], window=1024, steps=4,
                  val_every=2, restart_period=4, swa_start=2, workers=2, threads=2)
    (folder / 'recipe.yaml').write_text(yaml.safe_dump(recipe))
    assert main(['train', '--recipe', str(folder / 'recipe.yaml'), '--quiet', '--out',
                 str(folder / 'workers.safetensors')]) == 0
    return folder


def test_two_workers_train_on_synthetic_recordings_without_the_real_data(built_in):
    from denoise_imu_ros.core.modelfile import read_model_file
    meta = read_model_file(built_in / 'workers.safetensors').meta.raw
    assert meta['run']['workers'] == 2
    assert [h['step'] for h in meta['history']] == [0, 2, 4]
    assert all(np.isfinite(h['val_loss']) for h in meta['history'])
    assert not dist.is_initialized()


def test_torchrun_with_more_processes_than_sequences_is_one_clear_error(
        tmp_path, monkeypatch):
    from helpers import write_asl
    for i in range(2):
        write_asl(tmp_path / f'rec{i}', n_imu=2400, yaw_rate=0.2, gyro_bias=0.01)
    cfg = load_config(CONFIG, data=str(tmp_path), sequences=['rec0', 'rec1'], window=1024,
                      steps=4, restart_period=4, swa_start=2)
    monkeypatch.setattr(parallel, 'torchrun_rank', lambda: 2)
    monkeypatch.setattr(parallel, 'join_torchrun', lambda: (2, 3))  # rank 2 of 3
    monkeypatch.setattr(train_module.dist, 'destroy_process_group', lambda: None)
    with pytest.raises(TrainingError, match='torchrun started 3 processes for 2 training '
                                            'sequences'):
        train(cfg, progress=False)


def test_torchrun_trains_the_same_model_as_the_built_in_workers(built_in, tmp_path):
    """Issue 18: PyTorch's own launcher (env:// rendezvous) gives the --workers 2 model."""
    import os
    import subprocess
    import sys
    from denoise_imu_ros.core.modelfile import read_model_file
    env = {k: v for k, v in os.environ.items() if k not in ('RANK', 'WORLD_SIZE')}
    subprocess.run([sys.executable, '-m', 'torch.distributed.run', '--standalone',
                    '--nproc-per-node', '2', '-m', 'denoise_imu_ros.cli', 'train', '--recipe',
                    str(built_in / 'recipe.yaml'), '--quiet', '--out',
                    str(tmp_path / 'torchrun.safetensors')],
                   check=True, env=env, cwd=tmp_path, timeout=300)
    launched = read_model_file(tmp_path / 'torchrun.safetensors')
    built = read_model_file(built_in / 'workers.safetensors')
    assert launched.meta.raw['run']['workers'] == 2
    assert [h['val_loss'] for h in launched.meta.raw['history']] == [
        h['val_loss'] for h in built.meta.raw['history']]
    for name, array in built.arrays.items():
        np.testing.assert_array_equal(launched.arrays[name], array, err_msg=name)


def test_what_reading_the_recordings_warns_of_is_said_by_the_first_process_only(
        tmp_path, capfd):
    from denoise_imu_ros.core.errors import DataWarning
    from helpers import T0, write_asl
    (tmp_path / 'vio').mkdir()
    for i in range(2):
        write_asl(tmp_path / f'rec{i}', n_imu=2400, yaw_rate=0.2, gyro_bias=0.01)
        t = np.arange(0, 12.0, 0.05)
        rows = [f'{T0 * 1e-9 + s:.9f} 0 0 0 0 0 {np.sin(0.1 * s):.12f} {np.cos(0.1 * s):.12f}'
                for s in t]
        (tmp_path / 'vio' / f'rec{i}.txt').write_text('\n'.join(rows + rows[-1:]) + '\n')
    cfg = load_config(CONFIG, data=str(tmp_path), sequences=['rec0', 'rec1'], window=1024,
                      steps=2, val_every=2, restart_period=2, swa_start=1, workers=2,
                      poses=str(tmp_path / 'vio'))
    with pytest.warns(DataWarning, match='dropped 1 duplicate stamps'):
        train(cfg, progress=False)
    assert 'DataWarning' not in capfd.readouterr().err  # the worker process said nothing
