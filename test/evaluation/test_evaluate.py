# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""eval and correct: tables, figures, chunked batch correction."""

import json
import re

from denoise_imu_ros.cli import main
from denoise_imu_ros.data.load import load_imu
from denoise_imu_ros.learn import model as model_module
from denoise_imu_ros.learn.checkpoint import load_model
from denoise_imu_ros.learn.model import correct_gyro
from helpers import SAMPLE
import numpy as np
import pytest
import torch

SAMPLE_DIR = SAMPLE.parent


def test_chunked_correction_equals_one_batch_call(model_file, monkeypatch):
    model = load_model(model_file).model
    imu = load_imu(SAMPLE).imu[:5000]
    with torch.no_grad():
        whole = model(torch.tensor(imu, dtype=torch.float32)[None])[0].double().numpy()
    monkeypatch.setattr(model_module, 'CHUNK', 700)
    np.testing.assert_allclose(correct_gyro(model, imu), whole, rtol=0, atol=1e-6)


def test_eval_writes_json_markdown_and_figures(model_file, calib_file, tmp_path):
    out = tmp_path / 'eval'
    assert main(['eval', '--model', str(model_file), '--data', str(SAMPLE_DIR),
                 '--sequences', SAMPLE.name, '--out', str(out),
                 '--baseline', str(calib_file)]) == 0
    report = json.loads((out / 'results.json').read_text())
    seq = report['sequences'][SAMPLE.name]
    assert set(seq) == {'raw', 'rest bias', 'tracker only', 'calibrated', 'network'}
    assert set(seq['raw']['roe_median_deg']) == {'7', '21', '35'}
    assert seq['raw']['aoe_deg'] > 1
    assert (out / 'results.md').read_text().startswith('| method |')
    fused = report['fused'][SAMPLE.name]
    assert set(fused) == {'raw + VQF defaults', 'raw + VQF', 'rest bias + VQF',
                          'tracker only + VQF', 'calibrated + VQF',
                          'calibrated + imufusion',
                          'calibrated + Madgwick', 'network + VQF'}
    assert all(np.isfinite([f['aoe_deg'], f['tilt_deg'], f['tilt_growth_deg_min']]).all()
               for f in fused.values())
    assert 'Gravity-aided orientation' in (out / 'results.md').read_text()
    assert 'Tilt error growth' in (out / 'results.md').read_text()
    for png in (f'{SAMPLE.name}.png', 'roe.png'):
        assert (out / png).read_bytes()[:4] == b'\x89PNG'


def test_eval_of_a_short_recording_writes_strict_json_and_plots(
        model_file, calib_file, tmp_path):
    """Never 35 m travelled, and a name ending in '/'."""
    from helpers import write_asl
    write_asl(tmp_path / 'data' / 'base', n_imu=3000)  # 15 s turning on the spot
    out = tmp_path / 'eval'
    assert main(['eval', '--model', str(model_file), '--data', str(tmp_path / 'data'),
                 '--sequences', 'base/', '--out', str(out), '--baseline', str(calib_file)]) == 0
    text = (out / 'results.json').read_text()
    assert 'NaN' not in text and 'Infinity' not in text
    report = json.loads(text)
    assert report['sequences']['base']['network']['roe_median_deg'] == {
        '7': None, '21': None, '35': None}
    assert '- network: base –/–/–' in (out / 'results.md').read_text()  # not nan/nan/nan
    for png in ('base.png', 'roe.png'):
        assert (out / png).read_bytes()[:4] == b'\x89PNG'
    assert sorted(p.name for p in out.iterdir()) == ['base.png', 'results.json', 'results.md',
                                                     'roe.png']


def test_eval_says_when_it_scores_a_recording_the_model_was_fitted_on(
        tmp_path, calib_file, capsys):
    from helpers import write_untrained_model
    model = write_untrained_model(tmp_path / 'model.safetensors', {
        'dataset': 'test', 'sample_rate_hz': 200.0, 'train_sequences': [SAMPLE.name],
        'train_config': {'window': 1000, 'max_offset': 32}})
    out = tmp_path / 'eval'
    assert main(['eval', '--model', str(model), '--data', str(SAMPLE_DIR), '--sequences',
                 SAMPLE.name, '--out', str(out), '--baseline', str(calib_file), '--no-plots']) == 0
    warning = capsys.readouterr().err
    assert f'warning: {SAMPLE.name} was used to train this model (samples 0-1031)' in warning
    assert '--start-sample 1032' in warning
    assert json.loads((out / 'results.json').read_text())['training_fit_note'] in warning
    assert 'include that fit' in (out / 'results.md').read_text()


def test_only_a_training_recordings_fitted_span_is_flagged():
    from denoise_imu_ros.core.schema import parse_meta
    from denoise_imu_ros.evaluation.reports import scored_on_training_samples
    meta = parse_meta({'train_sequences': ['MH_01_easy'],
                       'train_config': {'window': 16000, 'max_offset': 32}}, 'm')
    names = ['MH_01_easy', 'data/MH_02_easy']
    assert scored_on_training_samples(meta, names, 0) == ['MH_01_easy']
    assert scored_on_training_samples(meta, names, 16031) == ['MH_01_easy']
    assert scored_on_training_samples(meta, names, 16032) == []  # the validation tail
    assert scored_on_training_samples(parse_meta({}, 'm'), names, 0) == []
    assert scored_on_training_samples(parse_meta({'train_sequences': ['MH_02_easy']}, 'm'),
                                      names, 10 ** 6) == ['data/MH_02_easy']  # span unknown


def test_one_recording_given_twice_is_refused_not_averaged_twice(model_file, tmp_path, capsys):
    assert main(['eval', '--model', str(model_file), '--data', str(SAMPLE_DIR), '--sequences',
                 SAMPLE.name, f'{SAMPLE.name}/', '--out', str(tmp_path / 'e')]) == 1
    assert f'--sequences: {SAMPLE.name} given twice' in capsys.readouterr().err


def test_a_model_file_without_a_sample_rate_is_refused_by_eval_and_correct(
        tmp_path, calib_file, capsys):
    from helpers import write_untrained_model
    model = write_untrained_model(tmp_path / 'norate.safetensors', {'dataset': 'test'})
    for cmd in (['eval', '--model', str(model), '--data', str(SAMPLE_DIR), '--sequences',
                 SAMPLE.name, '--out', str(tmp_path / 'e'), '--baseline', str(calib_file)],
                ['correct', '--model', str(model), '--input', str(SAMPLE),
                 '--out', str(tmp_path / 'c.csv'), '--engine', 'streaming']):
        assert main(cmd) == 1
        err = capsys.readouterr().err.strip()
        assert err.endswith('norate.safetensors: model file has no valid sample rate'), err
    assert not (tmp_path / 'c.csv').exists()


def test_a_baseline_that_is_a_network_or_of_another_rate_is_refused_by_every_command(
        model_file, tmp_path, capsys):
    from denoise_imu_ros.learn.checkpoint import save_model
    from helpers import untrained_model
    calib100 = tmp_path / 'calib100.safetensors'
    save_model(calib100, untrained_model(calibration_only=True), {'sample_rate_hz': 100.0})
    for baseline, why in ((model_file, 'a network, not a calibration (train '
                                       '--calibration-only makes one)'),
                          (calib100, 'a calibration of 100.00 Hz, the model model.safetensors '
                                     'is of 200.00 Hz')):
        for cmd in (['eval', '--out', str(tmp_path / 'e'), '--data', str(SAMPLE_DIR),
                     '--sequences', SAMPLE.name],
                    ['noise', '--out', str(tmp_path / 'n'), '--data', str(SAMPLE_DIR),
                     '--sequences', SAMPLE.name],
                    ['tune-fusion', '--data', str(SAMPLE_DIR)]):
            assert main([*cmd, '--model', str(model_file), '--baseline', str(baseline)]) == 1
            err = capsys.readouterr().err.strip()
            assert err.endswith(f'--baseline {baseline}: {why}'), err
            assert len(err.splitlines()) == 1


def test_figures_against_a_trajectory_say_its_own_noise_beside_them(euroc, tmp_path, capsys):
    """Motion capture written as a VIO writes it, once as it is, once 0.2 deg noisier."""
    from denoise_imu_ros.data.asl import read_asl
    from denoise_imu_ros.data.trajectory import write_tum
    from helpers import crop_asl
    from scipy.spatial.transform import Rotation
    data = tmp_path / 'euroc'  # MH_01's first 55 s: its still start and half a minute of flight
    rec = read_asl(crop_asl(euroc / 'MH_01_easy', data / 'MH_01_easy', 55))
    keep = slice(None, None, 10)  # 20 Hz, a VIO's rate
    rng = np.random.default_rng(0)
    noisy = Rotation.from_rotvec(np.radians(rng.normal(0, 0.2, (len(rec.gt_quat[keep]), 3))))
    for name, quat in (('clean', rec.gt_quat[keep]),
                       ('noisy', (Rotation.from_quat(rec.gt_quat[keep]) * noisy).as_quat())):
        write_tum(tmp_path / name / 'MH_01_easy.txt', rec.gt_stamp_ns[keep], rec.gt_pos[keep],
                  quat)
        assert main(['eval', '--model', 'euroc', '--data', str(data), '--sequences',
                     'MH_01_easy', '--poses', str(tmp_path / name), '--align', 'auto',
                     '--out', str(tmp_path / f'e_{name}'), '--no-plots']) == 0
    capsys.readouterr()
    said = {name: json.loads((tmp_path / f'e_{name}' / 'results.json').read_text())[
        'reference_noise_deg']['MH_01_easy'] for name in ('clean', 'noisy')}
    assert said['clean'] < 0.1 and 0.25 < said['noisy'] < 0.5  # 0.2 deg per axis: 0.35
    # the same poses as keyframes, 0.2-1.0 s apart: their noise (and their alignment's
    # error), not what interpolating between them misses (about 0.85 deg on the grid)
    t = (rec.gt_stamp_ns - rec.gt_stamp_ns[0]) * 1e-9
    wanted = np.cumsum(rng.uniform(0.2, 1.0, 1000))
    keyframes = np.unique(np.searchsorted(t, wanted[wanted < t[-1]]))
    write_tum(tmp_path / 'keyframes' / 'MH_01_easy.txt', rec.gt_stamp_ns[keyframes],
              rec.gt_pos[keyframes], rec.gt_quat[keyframes])
    assert main(['eval', '--model', 'euroc', '--data', str(data), '--sequences',
                 'MH_01_easy', '--poses', str(tmp_path / 'keyframes'), '--align', 'auto',
                 '--out', str(tmp_path / 'e_keyframes'), '--no-plots']) == 0
    assert json.loads((tmp_path / 'e_keyframes' / 'results.json').read_text())[
        'reference_noise_deg']['MH_01_easy'] < 0.25
    assert 'an estimate, not ground truth' in (tmp_path / 'e_noisy' / 'results.md').read_text()
    assert re.search(r"Poses moved onto the IMU's clock and frame first \(--align auto; t_imu = "
                     r't_pose \+ offset\): MH_01_easy [+-]0\.\d ms, 0\.\d\d deg\.',
                     (tmp_path / 'e_noisy' / 'results.md').read_text())
    assert main(['eval', '--model', 'euroc', '--data', str(data), '--sequences', 'MH_01_easy',
                 '--out', str(tmp_path / 'e_mocap'), '--no-plots']) == 0  # its own poses
    assert json.loads((tmp_path / 'e_mocap' / 'results.json').read_text())[
        'reference_noise_deg'] is None
    # said to be an estimate (a bag's odometry topic): its noise beside the figures too
    assert main(['eval', '--model', 'euroc', '--data', str(data), '--sequences', 'MH_01_easy',
                 '--out', str(tmp_path / 'e_said'), '--no-plots', '--estimated-poses']) == 0
    assert json.loads((tmp_path / 'e_said' / 'results.json').read_text())[
        'reference_noise_deg']['MH_01_easy'] < 0.1


def test_poses_that_start_after_the_stillness_score_what_the_node_publishes(tmp_path):
    """
    A VIO's trajectory starts after its initialisation, the still start before it.

    Every row runs from the recording's first IMU sample (the turn-on bias from the
    stillness, the tracker's state, the filters'), scored where the poses are: the figures
    of its own poses from the same sample on.
    """
    from denoise_imu_ros.core.schema import BiasTracking, RestBiasSettings
    from denoise_imu_ros.data.load import load_sequence
    from helpers import write_asl, write_late_trajectory, write_untrained_model
    asl = write_asl(tmp_path / 'rec', n_imu=3000, yaw_rate=0.2, gyro_bias=0.01, still_s=3.0)
    net = write_untrained_model(tmp_path / 'net.safetensors', {
        'sample_rate_hz': 200.0, 'rest_bias': RestBiasSettings().to_dict(),
        'bias_tracking': BiasTracking(0.05, 30.0).as_dict()})
    vio = write_late_trajectory(tmp_path / 'vio', asl, 4.0)
    k = len(load_sequence(asl, poses=vio).lead_in)
    assert k == 800
    for name, extra in (('late', ['--poses', str(vio)]), ('own', ['--start-sample', str(k)])):
        assert main(['eval', '--model', str(net), '--data', str(tmp_path), '--sequences', 'rec',
                     '--out', str(tmp_path / name), '--no-plots', '--align', 'none', *extra]) == 0
    late, own = (json.loads((tmp_path / n / 'results.json').read_text()) for n in ('late', 'own'))
    for part in ('sequences', 'fused'):
        for method, figures in own[part]['rec'].items():
            for key in ('aoe_deg', 'tilt_deg'):
                assert late[part]['rec'][method][key] == pytest.approx(
                    figures[key], rel=1e-4, abs=1e-6), (part, method, key)
    # the turn-on bias was found in the stillness before the poses: none left to drift
    assert late['sequences']['rec']['rest bias']['aoe_deg'] < 0.05
    assert late['sequences']['rec']['raw']['aoe_deg'] > 1.0
