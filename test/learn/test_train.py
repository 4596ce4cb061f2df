# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""A few training steps on short real segments: the loss goes down, failures are clear."""

import dataclasses
from pathlib import Path

from denoise_imu_ros.cli import main
from denoise_imu_ros.core.errors import DatasetError, TrainingError
from denoise_imu_ros.data.load import load_imu, load_sequence
from denoise_imu_ros.learn import train as train_module
from denoise_imu_ros.learn.checkpoint import load_model
from denoise_imu_ros.learn.config import load_config
from denoise_imu_ros.learn.train import batch, batch_loss, build_model, train, training_split
from helpers import ROOT
import numpy as np
import pytest
import torch
import yaml

CONFIG = ROOT / 'config' / 'train_euroc.yaml'


def _short(euroc, **changes):
    """Return the EuRoC recipe on two sequences with 10 s windows and a few steps."""
    changes = {'swa_start': 12, 'sequences': ['MH_01_easy', 'V1_02_medium'], 'steps': 24,
               'val_every': 12, 'data': str(euroc), **changes}
    return load_config(CONFIG, window=2048, restart_period=24, **changes)


def test_a_few_steps_on_real_data_lower_the_validation_loss(euroc, tmp_path):
    result = train(_short(euroc), progress=False)
    result.save(tmp_path / 'chosen.safetensors', candidates_dir=tmp_path)
    meta = result.meta
    history = meta['history']
    assert [h['step'] for h in history] == [0, 12, 24]
    assert history[-1]['val_loss'] < 0.5 * history[0]['val_loss']
    assert meta['validation']['step'] in (12, 24)
    assert meta['selected'] == 'swa'  # the recipe's choice
    assert meta['validation'] == meta['candidates']['swa']
    for name in ('best_checkpoint', 'final', 'swa'):
        cand = load_model(tmp_path / f'{name}.safetensors')
        assert cand.meta.validation.loss == meta['candidates'][name]['loss']
    assert meta['train_sequences'] == ['MH_01_easy', 'V1_02_medium']
    assert 199 < meta['sample_rate_hz'] < 201
    assert len(meta['validation']['gyro_residual_std']) == 3
    # the motion trained on, that the runtime holds the correction beyond
    envelope = load_model(tmp_path / 'chosen.safetensors').meta.input_envelope
    assert 0.5 < envelope.gyro_rad_s < 10 and 0.5 < envelope.accel_offset_m_s2 < 50
    # and how long it accelerated, over the training recordings whole
    from denoise_imu_ros.pipeline.envelope import sustained_bound
    assert envelope.sustained_accel_m_s2 == sustained_bound(
        [load_sequence(euroc / n).imu for n in meta['train_sequences']], meta['sample_rate_hz'])
    assert envelope.sustained_accel_m_s2 < envelope.accel_offset_m_s2


def test_twenty_hz_ground_truth_trains_with_a_finite_falling_loss(euroc, tmp_path):
    # V1_01's corrected ground truth (OpenVINS) is a 20 Hz trajectory
    cfg = _short(euroc, sequences=['V1_01_easy'], val_every=6, swa_start=0,
                 select='final')
    meta = train(cfg, progress=False).meta
    losses = [h['train_loss'] for h in meta['history'][1:]]
    assert all(np.isfinite(v) and v > 0 for v in losses)
    assert losses[-1] < 0.5 * losses[0]
    # 24 steps on one recording: over dropout draws the validation loss ends at 0.13-0.88
    # of its start (seeds 0-3, either layer path)
    assert meta['history'][-1]['val_loss'] < 0.9 * meta['history'][0]['val_loss']


def test_twenty_hz_ground_truth_trains_between_its_poses(euroc):
    cfg = _short(euroc, sequences=['V1_01_easy'], val_every=6, swa_start=0, select='final',
                 increments_between_poses=True)
    assert cfg.loss_config().between_poses
    meta = train(cfg, progress=False).meta
    losses = [h['train_loss'] for h in meta['history'][1:]]
    assert all(np.isfinite(v) and v > 0 for v in losses)
    assert losses[-1] < 0.5 * losses[0]
    seq = load_sequence(euroc / 'V1_01_easy')
    assert 0.09 < seq.pose_at.mean() < 0.11  # every 10th sample of 200 Hz has a pose
    # poses trusted nowhere between them: nothing to compare, said as for the grid
    with pytest.raises(TrainingError, match='V1_01_easy: no 16-sample increment between '
                                            'poses with trusted ground truth in its training '
                                            'window'):
        train(dataclasses.replace(cfg, max_gt_gap_s=0.02), progress=False)


def test_a_recording_that_cannot_supervise_the_loss_is_named(euroc, tmp_path):
    cfg = _short(euroc, sequences=['MH_01_easy', 'V1_01_easy'], max_gt_gap_s=0.02)
    with pytest.raises(TrainingError, match='V1_01_easy: no 16-sample increment with trusted '
                                            'ground truth in its training window'):
        train(cfg, progress=False)


def test_recordings_of_different_rates_are_refused(euroc, tmp_path):
    import dataclasses
    from denoise_imu_ros.data.asl import read_asl
    from denoise_imu_ros.data.bags import write_bag
    (tmp_path / 'MH_01_easy').symlink_to(euroc / 'MH_01_easy')
    rec = read_asl(euroc / 'V1_02_medium')
    write_bag(dataclasses.replace(rec, imu_stamp_ns=rec.imu_stamp_ns[::2], imu=rec.imu[::2]),
              tmp_path / 'V1_02_at_100_hz')
    cfg = _short(euroc, data=str(tmp_path), sequences=['MH_01_easy', 'V1_02_at_100_hz'])
    with pytest.raises(DatasetError, match=r'differ \(MH_01_easy 200.0 Hz, V1_02_at_100_hz '
                                           r'100.0 Hz\): one model is for one rate'):
        train(cfg, progress=False)


def test_non_finite_loss_stops_with_a_clear_message(euroc, monkeypatch):
    real = train_module.increment_loss
    monkeypatch.setattr(train_module, 'increment_loss',
                        lambda *a, **k: real(*a, **k) * float('nan'))
    with pytest.raises(TrainingError, match='non-finite training loss at step 1'):
        train(_short(euroc), progress=False)


def test_a_network_that_diverged_on_its_validation_tails_is_one_line(tmp_path):
    from denoise_imu_ros.core.architecture import ModelConfig
    from denoise_imu_ros.learn.loss import LossConfig
    from denoise_imu_ros.learn.model import GyroNet
    from helpers import write_asl
    seq = load_sequence(write_asl(tmp_path / 'rec', n_imu=2000))
    model = GyroNet(ModelConfig())
    model.net[-1].bias.data[:] = float('inf')
    with pytest.raises(TrainingError, match='rec: the network gives non-finite rates on its '
                                            'validation tail: the training diverged'):
        train_module.validate(model, [seq], 1000, LossConfig())


def test_a_heading_less_model_is_validated_as_every_path_ends_it():
    """Its AOE on the tails is of its output less its correction about the vertical."""
    from denoise_imu_ros.core.metrics import sequence_errors
    from denoise_imu_ros.pipeline.vertical import drop_vertical
    from denoise_imu_ros.learn.loss import LossConfig
    from denoise_imu_ros.learn.model import correct_gyro
    from helpers import SAMPLE, untrained_model
    seq = load_sequence(SAMPLE)
    model = untrained_model()
    kept = train_module.validate(model, [seq], 9000, LossConfig())
    dropped = train_module.validate(model, [seq], 9000, LossConfig(), drop=True)
    assert dropped['loss'] == kept['loss']  # the loss never sees the vertical
    omega = correct_gyro(model, seq.imu).astype(np.float64)
    expected = sequence_errors(seq.tail(9000), drop_vertical(omega, seq.imu, seq.rate_hz)[9000:],
                               distances=())[1].aoe
    assert dropped['aoe_mean_deg'] == pytest.approx(expected, abs=1e-6)
    assert abs(dropped['aoe_mean_deg'] - kept['aoe_mean_deg']) > 1e-3


def test_calibration_baseline_trains_from_the_same_command(euroc, tmp_path):
    cfg = yaml.safe_load(CONFIG.read_text())
    cfg.update(sequences=['MH_01_easy'], window=1024, steps=6, val_every=6, swa_start=3)
    (tmp_path / 'c.yaml').write_text(yaml.safe_dump(cfg))
    out = tmp_path / 'calib.safetensors'
    assert main(['train', '--recipe', str(tmp_path / 'c.yaml'), '--data', str(euroc),
                 '--calibration-only', '--quiet', '--out', str(out)]) == 0
    loaded = load_model(out)
    assert loaded.model.num_trainable() == 12
    assert loaded.meta.recipe('calibration_only') is True


def test_data_parallel_processes_draw_the_one_process_batch(euroc):
    cfg = _short(euroc, workers=1)
    seqs = [load_sequence(euroc / name) for name in cfg.sequences]
    _, split, gen = build_model(cfg, seqs, 0)
    one = batch(split, cfg, gen)
    two = dataclasses.replace(cfg, workers=2)
    for rank in (0, 1):
        _, split, gen = build_model(two, seqs, rank)
        for whole, part in zip(one, batch(split, two, gen)):
            assert torch.equal(whole[rank::2], part)


@pytest.mark.parametrize('kept', [False, True])
def test_a_kept_gyro_bias_is_passed_through_not_learnt(euroc, kept):
    # an untrained calibration is the identity: it passes every offset through, which is
    # right when the drawn bias is kept in the target and an error to learn when it is not
    cfg = _short(euroc, calibration_only=True, gyro_noise=0.0, accel_noise=0.0,
                 gyro_bias_kept=kept, workers=2)  # rank 0's share: MH_01, on any machine
    seqs = [load_sequence(euroc / name) for name in cfg.sequences]
    model, split, _ = build_model(cfg, seqs, 0)
    loss = {}
    for bias in (0.0, 0.1):
        drawn = batch(split, dataclasses.replace(cfg, gyro_bias=bias),
                      torch.Generator().manual_seed(0))
        u_gyro, applied = drawn[0][..., :3], drawn[-1]
        unbiased = batch(split, dataclasses.replace(cfg, gyro_bias=0.0),
                         torch.Generator().manual_seed(0))[0][..., :3]
        torch.testing.assert_close(applied.expand_as(u_gyro), u_gyro - unbiased)
        with torch.no_grad():
            loss[bias] = batch_loss(model, drawn, cfg, None, split.mine).item()
    if kept:
        assert loss[0.1] == pytest.approx(loss[0.0], rel=1e-3)
    else:
        assert loss[0.1] > 1.3 * loss[0.0]


def test_whole_sequence_windows_are_normalised_without_the_padding(tmp_path):
    from helpers import write_asl
    for name, n, rate in (('short', 2400, 0.3), ('long', 6000, 0.6)):
        write_asl(tmp_path / name, n_imu=n, yaw_rate=rate)
    cfg = load_config(CONFIG, data=str(tmp_path), sequences=['short', 'long'], window=1024,
                      whole_sequences=True, steps=4, restart_period=4, swa_start=2)
    seqs = [load_sequence(tmp_path / name) for name in cfg.sequences]
    model = build_model(cfg, seqs, 0)[0]
    samples = np.concatenate([s.imu for s in seqs])
    np.testing.assert_allclose(model.input_mean.numpy(), samples.mean(0), rtol=1e-5,
                               atol=1e-6)
    np.testing.assert_allclose(model.input_std[2].item(), samples[:, 2].std(), rtol=1e-4)


@pytest.mark.parametrize('whole', [False, True])
def test_windows_are_drawn_from_the_head_or_the_whole_of_each_sequence(euroc, whole):
    cfg = _short(euroc, whole_sequences=whole)
    seqs = [load_sequence(euroc / name) for name in cfg.sequences]
    split = training_split(seqs, cfg)
    gen = torch.Generator().manual_seed(0)
    last_stamp_seen = [0] * len(seqs)
    for _ in range(300):
        u, dt, quat, valid, pose_at, _ = batch(split, cfg, gen)
        assert u.shape == (2, cfg.window, 6) and quat.shape == (2, cfg.window + 1, 4)
        assert bool(valid.all()) and bool((dt > 0).all())  # never the zero padding
        for i, s in enumerate(seqs):
            # find where this window ends in the sequence from its last quaternion
            end = int(np.flatnonzero((s.gt_quat == quat[i, -1].numpy()).all(1))[0])
            last_stamp_seen[i] = max(last_stamp_seen[i], end)
            assert np.array_equal(pose_at[i].numpy(), s.pose_at[end - cfg.window:end + 1])
    for s, end in zip(seqs, last_stamp_seen):
        if whole:
            assert end > len(s) - 2000  # windows reach the end of every sequence
        else:
            assert end < cfg.window + cfg.max_offset


def test_an_unwritable_output_is_refused_before_training(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(train_module, 'load_sequences', lambda cfg: pytest.fail('trained'))
    (tmp_path / 'file').write_text('')
    assert main(['train', '--recipe', str(CONFIG), '--out',
                 str(tmp_path / 'file' / 'model.safetensors')]) == 1
    err = capsys.readouterr().err
    assert 'cannot create the output folder' in err and len(err.splitlines()) == 1


def test_align_auto_trains_on_poses_of_a_rotated_marker_on_a_late_clock(euroc, tmp_path):
    import dataclasses
    from denoise_imu_ros.data.asl import read_asl
    from denoise_imu_ros.data.bags import write_bag
    from scipy.spatial.transform import Rotation
    rec = read_asl(euroc / 'V1_02_medium')
    marker = Rotation.from_rotvec([20.0, -35.0, 60.0], degrees=True)  # imu_from_pose
    moved = dataclasses.replace(rec, gt_stamp_ns=rec.gt_stamp_ns - 23_000_000,
                                gt_quat=(Rotation.from_quat(rec.gt_quat) * marker).as_quat())
    write_bag(moved, tmp_path / 'moved')
    original = load_sequence(euroc / 'V1_02_medium')
    fixed = load_sequence(tmp_path / 'moved', align_poses='auto')
    assert abs(fixed.pose_alignment['time_offset_s'] - 0.023) < 1e-3
    common, i, j = np.intersect1d(original.stamp_ns, fixed.stamp_ns, return_indices=True)
    err = (Rotation.from_quat(original.gt_quat[i]).inv()
           * Rotation.from_quat(fixed.gt_quat[j])).magnitude()
    assert len(common) > 0.9 * len(original) and np.degrees(err[fixed.gt_valid[j]]).max() < 0.2
    cfg = _short(euroc, data=str(tmp_path), sequences=['moved'], steps=6, val_every=6,
                 swa_start=3, align='auto', rest_bias=True)
    meta = train(cfg, progress=False).meta
    assert meta['train_config']['align'] == 'auto'
    # the turn-on bias prior from the bag's whole IMU stream, as from the ASL folder's
    prior = train_module.without_turn_on_bias(
        _short(euroc, sequences=['V1_02_medium'], rest_bias=True), [original])[1].prior_rad_s
    assert meta['rest_bias']['prior_rad_s'] == pytest.approx(prior, abs=1e-12)
    used = meta['pose_alignment']['moved']
    assert abs(used['time_offset_s'] - 0.023) < 1e-3
    assert len(used['imu_from_pose_rotation_xyzw']) == 4
    with pytest.raises(TrainingError, match='align must be none, auto or a mapping'):
        _short(euroc, align='yes')


def _finished_training(monkeypatch):
    """Make `train` return at once with a finished (untrained) result."""
    from helpers import untrained_model
    result = train_module.TrainResult(untrained_model(), {
        'selected': 'swa', 'train_seconds': 1.0, 'sample_rate_hz': 200.0,
        'validation': {'step': 1, 'loss': 1.0, 'aoe_mean_deg': 1.0}}, {}, {})
    monkeypatch.setattr(train_module, 'train', lambda cfg, progress: result)


def test_a_finished_training_is_never_lost_when_its_output_cannot_be_written(
        tmp_path, capsys, monkeypatch):
    """The save fails (a full disk): the model is kept elsewhere, said so."""
    from denoise_imu_ros.core.errors import OutputError
    _finished_training(monkeypatch)
    out = tmp_path / 'model.safetensors'
    real = train_module.save_model

    def full_disk(path, model, meta):
        if Path(path) == out:
            raise OutputError(f'{path}: cannot write the model file (No space left on device)')
        real(path, model, meta)
    monkeypatch.setattr(train_module, 'save_model', full_disk)
    assert main(['train', '--recipe', str(CONFIG), '--out', str(out)]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and 'No space left on device' in err
    kept = Path(err.split('the trained model was kept at ')[1])
    assert kept.name == 'model.safetensors' and load_model(kept).meta.raw['selected'] == 'swa'


def test_ctrl_c_stops_with_one_line_and_exit_code_130(tmp_path, capsys, monkeypatch):
    """Ctrl-C during a training: one line on stderr, exit code 130, no traceback."""
    def interrupted(cfg, progress):
        raise KeyboardInterrupt
    monkeypatch.setattr(train_module, 'train', interrupted)
    assert main(['train', '--recipe', str(CONFIG), '--out', str(tmp_path / 'm.safetensors')]) \
        == 130
    assert capsys.readouterr().err.strip() == 'denoise-imu train: interrupted'


def test_the_prior_and_the_turn_on_bias_are_measured_before_the_poses_start_too(
        euroc, tmp_path):
    """A trajectory that starts after the still start (a VIO's initialisation): same input."""
    from denoise_imu_ros.pipeline import rest_bias
    mav = tmp_path / 'MH_01_easy' / 'mav0'
    (mav / 'state_groundtruth_estimate0').mkdir(parents=True)
    (mav / 'imu0').symlink_to(euroc / 'MH_01_easy' / 'mav0' / 'imu0')
    lines = (euroc / 'MH_01_easy' / 'mav0' / 'state_groundtruth_estimate0' / 'data.csv'
             ).read_text().splitlines(keepends=True)
    late = int(lines[1].split(',')[0]) + 40 * 10 ** 9  # poses from 40 s in, moving
    (mav / 'state_groundtruth_estimate0' / 'data.csv').write_text(''.join(
        [lines[0]] + [ln for ln in lines[1:] if int(ln.split(',')[0]) >= late]))
    cfg = _short(euroc, rest_bias=True, sequences=['MH_01_easy'])
    whole = train_module.without_turn_on_bias(cfg, train_module.load_sequences(cfg))[1]
    cut = dataclasses.replace(cfg, data=str(tmp_path))
    seqs = train_module.load_sequences(cut)
    assert len(seqs[0].imu) < len(load_imu(euroc / 'MH_01_easy').imu) - 40 * 190
    fed, settings = train_module.without_turn_on_bias(cut, seqs)
    assert settings == whole
    own = train_module.without_turn_on_bias(cfg, train_module.load_sequences(cfg))[0][0]
    assert np.array_equal(fed[0].stream, own.stream)  # the model's input from sample 0 on
    wide = dataclasses.replace(rest_bias.RestBiasSettings(),
                               bias_clip_deg_s=rest_bias.WIDE_CLIP_DEG_S)
    # from the samples with poses alone it would differ
    assert rest_bias.nominal_bias([seqs[0].imu], 200.0, wide)[0] != whole.prior_rad_s


def test_a_rest_bias_recipe_trains_on_each_recording_less_its_turn_on_bias(euroc, tmp_path):
    from denoise_imu_ros.pipeline import rest_bias
    cfg = _short(euroc, rest_bias=True, steps=12, val_every=12, swa_start=0, select='final')
    raw = train_module.load_sequences(cfg)
    seqs, settings = train_module.without_turn_on_bias(cfg, raw)
    wide = dataclasses.replace(rest_bias.RestBiasSettings(),
                               bias_clip_deg_s=rest_bias.WIDE_CLIP_DEG_S)
    rate = float(np.median([s.rate_hz for s in raw]))  # the model file's rate
    nominal = rest_bias.nominal_bias(
        [load_imu(euroc / name).imu for name in cfg.sequences], rate, wide)
    assert nominal.still >= 1 and settings.prior_rad_s == nominal.prior_rad_s
    # EuRoC's ADIS16448 has a 4.6 deg/s turn-on bias about z, its power-ons within a few
    # tenths of each other: the clip about the prior is VQF's 2 deg/s, or their spread's
    assert settings.bias_clip_deg_s == max(2.0, 4 * np.degrees(nominal.spread_rad_s))
    for s, r in zip(seqs, raw):  # the estimate runs from the first IMU sample, as online
        stream = rest_bias.remove_rest_bias(r.stream, rate, settings)
        assert len(r.lead_in) and np.array_equal(s.stream, stream)
        assert np.array_equal(s.imu, r.on_poses(stream))
    assert train_module.without_turn_on_bias(dataclasses.replace(cfg, rest_bias=False), raw) == (
        raw, None)
    result = train(cfg, progress=False)
    result.save(tmp_path / 'rest.safetensors')
    stored = load_model(tmp_path / 'rest.safetensors').meta.rest_bias
    assert stored == settings


@pytest.mark.parametrize('workers', [1, 2])
def test_each_recording_s_constant_bias_is_learnt_apart_from_the_model(tmp_path, workers):
    """recording_bias: a constant that differs between recordings stays out of the model."""
    from helpers import write_asl
    biases = (0.02, -0.03)  # rad/s about z; never still, so the rest estimate stays at 0
    for i, b in enumerate(biases):
        write_asl(tmp_path / f'rec{i}', n_imu=2400, yaw_rate=0.3, gyro_bias=b)
    common = {'data': str(tmp_path), 'sequences': ['rec0', 'rec1'], 'window': 1024,
              'steps': 60, 'val_every': 30, 'restart_period': 60, 'swa_start': 0,
              'select': 'final', 'lr': 0.05, 'calibration_only': True, 'rest_bias': True,
              'workers': workers}
    result = train(load_config(CONFIG, recording_bias=True, **common), progress=False)
    learnt = result.meta['recording_bias_rad_s']
    assert list(learnt) == ['rec0', 'rec1']
    assert torch.equal(result.model.bias, torch.zeros(3))  # held at 0: not the model's
    # each recording's own offset takes its bias (the scale makes up the shared part)
    difference = np.subtract(learnt['rec0'], learnt['rec1'])
    np.testing.assert_allclose(difference, [0.0, 0.0, biases[1] - biases[0]], atol=2e-3)
    if workers == 1:  # without it, the model's one bias fits neither recording
        plain = train(load_config(CONFIG, **common), progress=False)
        assert plain.meta['recording_bias_rad_s'] is None
        assert plain.meta['history'][-1]['train_loss'] > 10 * result.meta['history'][-1][
            'train_loss']


def test_a_network_learning_recording_biases_keeps_its_output_layer_s_bias_at_zero(euroc):
    cfg = _short(euroc, rest_bias=True, recording_bias=True, steps=6, val_every=6,
                 swa_start=0, select='final')
    result = train(cfg, progress=False)
    assert torch.equal(result.model.net[-1].bias, torch.zeros(3))
    assert set(result.meta['recording_bias_rad_s']) == {'MH_01_easy', 'V1_02_medium'}


def test_a_gyro_only_network_s_output_does_not_move_with_the_accelerometer(euroc):
    """accel_input: false: whatever the weights, the correction is the gyro's alone."""
    cfg = _short(euroc, accel_input=False)
    seqs = [load_sequence(euroc / name) for name in cfg.sequences]
    model = build_model(cfg, seqs, rank=0)[0].eval()
    u = torch.tensor(seqs[0].imu[:2000], dtype=torch.float32)[None]
    shaken = u.clone()
    shaken[..., 3:] += 80.0 * torch.randn_like(shaken[..., 3:])
    with torch.no_grad():
        torch.testing.assert_close(model(shaken), model(u), rtol=0, atol=1e-6)
        both = build_model(_short(euroc), seqs, rank=0)[0].eval()
        assert (both(shaken) - both(u)).abs().max() > 1e-3  # the accelerometer counts there


def test_the_published_gyro_residual_of_keyframes_is_judged_between_their_stamps(euroc):
    from denoise_imu_ros.core.architecture import ModelConfig
    from denoise_imu_ros.data.asl import read_asl
    from denoise_imu_ros.data.timebase import onto_imu_stamps
    from denoise_imu_ros.learn.config import LossConfig
    from denoise_imu_ros.learn.model import GyroNet
    from denoise_imu_ros.learn.train import validate
    model = GyroNet(ModelConfig(calibration_only=True))  # the raw gyro, as it is
    model.set_normalization(torch.zeros(6), torch.ones(6))
    rec = read_asl(euroc / 'MH_01_easy')
    t = (rec.gt_stamp_ns - rec.gt_stamp_ns[0]) * 1e-9
    wanted = np.cumsum(np.random.default_rng(4).uniform(0.2, 1.0, 1000))
    keep = np.unique(np.searchsorted(t, wanted[wanted < t[-1]]))  # keyframes
    keyframes = onto_imu_stamps(dataclasses.replace(
        rec, gt_stamp_ns=rec.gt_stamp_ns[keep], gt_quat=rec.gt_quat[keep],
        gt_pos=rec.gt_pos[keep]))
    grid, between = (validate(model, [keyframes], 20000, LossConfig(
        increments=(256, 512), between_poses=b))['gyro_residual_std'] for b in (False, True))
    # on the grid what interpolation misses between keyframes counts as the gyro's error
    # (the node publishes this as the covariance of imu/corrected)
    assert all(b < 0.5 * g for b, g in zip(between, grid))
