# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Cross-recording validation: folds by recording, scores of unseen ones, the verdict."""

import json

from denoise_imu_ros.cli import main
from denoise_imu_ros.core.errors import TrainingError
from denoise_imu_ros.core.schema import judged_on, parse_meta, tracking_from_dict
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.evaluation.crossval import (attach_mismatches, BLEND_WEIGHTS, crossval, folds,
                                                 summarize)
from denoise_imu_ros.evaluation.filters import TILT_LABEL
from denoise_imu_ros.evaluation.reports import crossval_table
from denoise_imu_ros.learn.checkpoint import load_model
from helpers import write_asl
import pytest
import yaml


def _figures(net, calib, raw):
    return {m: {'aoe_deg': v, 'aoe_yaw_deg': v / 2, 'tilt_deg': v / 3}
            for m, v in (('network', net), ('calibrated', calib), ('raw', raw))}


def test_folds_hold_every_recording_out_exactly_once():
    names = ['a', 'b', 'c', 'd', 'e']
    assert folds(names) == [['a'], ['b'], ['c'], ['d'], ['e']]
    assert sorted(sum(folds(names, 2), [])) == names and len(folds(names, 2)) == 2
    with pytest.raises(TrainingError, match='folds must be between 2 and 5'):
        folds(names, 1)
    with pytest.raises(TrainingError, match='needs at least two recordings in the recipe'):
        folds(['a'])


def test_verdict_follows_the_figures():
    wins = summarize({'a': _figures(1.0, 2.0, 9.0), 'b': _figures(1.5, 2.0, 9.0),
                      'c': _figures(3.0, 2.0, 9.0)})
    assert wins['mean']['network']['aoe_deg'] == pytest.approx(5.5 / 3)
    assert wins['verdict'] == ('the network beats the calibrated IMU on 2 of 3 unseen '
                               'recordings, by 8 % in mean AOE: deploy the network')
    assert wins['deploy'] == 'network'
    loses = summarize({'a': _figures(1.0, 2.0, 9.0), 'b': _figures(4.0, 2.0, 9.0)})
    assert loses['verdict'].endswith('(1 of 2, -25 % in mean AOE): deploy the calibration')
    assert loses['deploy'] == 'calibration'
    # an IMU calibrated already: plain integration is the bar, not a refitted calibration
    plain = summarize({'a': _figures(1.2, 3.0, 1.0), 'b': _figures(1.1, 3.0, 1.0)})
    assert plain['verdict'].startswith('the calibration is 3.00x plain integration on a')
    assert 'the network is 1.20x plain integration on a (more than 1.1x' in plain['verdict']
    assert plain['verdict'].endswith('deploy no correction') and plain['deploy'] == 'none'
    # another power-on: the raw gyro less its turn-on bias is the bar when it is the best
    rest = {'raw': {'aoe_deg': 40.0, 'aoe_yaw_deg': 20.0, 'tilt_deg': 0.0},
            'rest bias': {'aoe_deg': 3.0, 'aoe_yaw_deg': 2.0, 'tilt_deg': 0.0}}
    after = summarize({'a': dict(_figures(3.5, 30.0, 40.0), **rest),
                       'b': dict(_figures(2.0, 30.0, 40.0), **rest)})
    assert after['mean']['rest bias']['aoe_deg'] == 3.0
    assert ('the network is 1.17x the raw gyro less its turn-on bias on a (more than 1.1x'
            in after['verdict'])
    assert after['deploy'] == 'rest bias'
    assert after['verdict'].endswith('only the turn-on bias removed (rest_bias)')
    # recordings never still: the rest bias is the raw gyro, and the simpler is deployed
    same = {'raw': {'aoe_deg': 1.4, 'aoe_yaw_deg': 1.2, 'tilt_deg': 0.0},
            'rest bias': {'aoe_deg': 1.4, 'aoe_yaw_deg': 1.2, 'tilt_deg': 0.0}}
    never_still = summarize({'a': dict(_figures(2.1, 2.0, 1.4), **same)})
    assert never_still['deploy'] == 'none'


def test_a_learnt_row_never_loses_to_the_classical_pipeline_on_one_recording():
    """A better mean from a few large wins does not hide a loss beyond 10 % elsewhere."""
    def rows(net: float, calib: float, tracker: float) -> dict[str, dict[str, float]]:
        return {'raw': {'aoe_deg': 40.0, 'aoe_yaw_deg': 30.0, 'tilt_deg': 1.0},
                'rest bias': {'aoe_deg': 5.0, 'aoe_yaw_deg': 4.0, 'tilt_deg': 1.0},
                **{m: {'aoe_deg': v, 'aoe_yaw_deg': v, 'tilt_deg': 1.0} for m, v in (
                    ('network', net), ('calibrated', calib), ('tracker only', tracker))}}
    few_large = summarize({'a': rows(2.0, 9.0, 10.0), 'b': rows(1.2, 2.0, 1.0),
                           'c': rows(0.9, 2.0, 1.0)})
    assert few_large['mean']['network']['aoe_deg'] < few_large['mean']['tracker only']['aoe_deg']
    assert few_large['deploy'] == 'tracker only'
    assert few_large['verdict'].startswith(
        'the calibration is 2.00x the classical pipeline (the gyro less its turn-on bias, its '
        'bias tracked, no model) on b')
    assert 'the network is 1.20x the classical pipeline' in few_large['verdict']
    assert few_large['verdict'].endswith('deploy no learnt correction: the turn-on bias '
                                         'removed and the bias left tracked (tracker only)')
    within = summarize({'a': rows(2.0, 9.0, 10.0), 'b': rows(1.05, 2.0, 1.0),
                        'c': rows(0.9, 2.0, 1.0)})
    assert within['deploy'] == 'network'
    assert within['verdict'] == ('the calibration is 2.00x the classical pipeline (the gyro '
                                 'less its turn-on bias, its bias tracked, no model) on b '
                                 '(more than 1.1x on one recording): not deployed; the network '
                                 'beats the classical pipeline (the gyro less its turn-on bias,'
                                 ' its bias tracked, no model) on 2 of 3 unseen recordings, by '
                                 '67 % in mean AOE: deploy the network')


def test_one_recording_where_the_tracker_diverges_does_not_make_the_rest_bias_the_bar():
    """On BROAD's session folds tracker only wins 9 of 12 trials and loses its mean on one."""
    def rows(rest: float, tracker: float, net: float) -> dict[str, dict[str, float]]:
        return {m: {'aoe_deg': v, 'aoe_yaw_deg': v, 'tilt_deg': 1.0} for m, v in (
            ('raw', 40.0), ('rest bias', rest), ('tracker only', tracker), ('calibrated', 9.0),
            ('network', net))}
    report = summarize({'a': rows(4.0, 1.5, 1.6), 'b': rows(4.3, 1.1, 3.1),
                        'c': rows(11.0, 29.0, 10.0), 'd': rows(3.0, 1.2, 1.1)})
    assert report['mean']['rest bias']['aoe_deg'] < report['mean']['tracker only']['aoe_deg']
    assert report['deploy'] == 'tracker only'
    # the per-recording bar is tracker only, not the rest bias it beats by 1.4x on b
    assert 'the network is 2.82x the classical pipeline' in report['verdict'] and ' on b ' in (
        report['verdict'])
    within = summarize({'a': rows(4.0, 1.5, 1.4), 'b': rows(4.3, 1.1, 1.0),
                        'c': rows(11.0, 29.0, 10.0)})
    assert within['deploy'] == 'network'
    assert within['verdict'].startswith('the calibration is ') and within['verdict'].endswith(
        'beats the classical pipeline (the gyro less its turn-on bias, its bias tracked, no '
        'model) on 3 of 3 unseen recordings, by 61 % in mean AOE: deploy the network')


def test_a_recipe_that_leaves_the_heading_out_is_judged_on_the_tilt_alone():
    """Against a VIO's poses the whole-recording AOE is mostly their own heading drift."""
    assert judged_on(1.0) == judged_on(2.0) == ('aoe_deg', None)
    assert judged_on(0.5)[0] == 'tilt_deg'
    key, why = judged_on(0.0)
    assert key == 'tilt_deg' and 'heading_weight 0' in why and 'not judged' in why
    drifted = {'a': {'rest bias': {'aoe_deg': 9.0, 'aoe_yaw_deg': 7.0, 'tilt_deg': 5.0},
                     'raw': {'aoe_deg': 90.0, 'aoe_yaw_deg': 80.0, 'tilt_deg': 40.0},
                     'calibrated': {'aoe_deg': 11.0, 'aoe_yaw_deg': 10.5, 'tilt_deg': 4.0},
                     'network': {'aoe_deg': 11.5, 'aoe_yaw_deg': 11.0, 'tilt_deg': 3.5}}}
    assert summarize(drifted)['deploy'] == 'rest bias'
    tilt = summarize(drifted, 'tilt_deg')
    assert tilt['deploy'] == 'network' and tilt['mean']['network']['tilt_deg'] == 3.5
    assert tilt['verdict'] == ('the network beats the calibrated IMU on 1 of 1 unseen '
                               'recordings, by 12 % in mean tilt error: deploy the network')
    # a heading the poses' drift cannot explain (more than twice the rest bias's): not deployed
    ruined = {'a': dict(drifted['a'], network={'aoe_deg': 16.0, 'aoe_yaw_deg': 15.0,
                                               'tilt_deg': 3.5})}
    assert summarize(ruined, 'tilt_deg')['deploy'] == 'calibration'
    ruined['a']['calibrated'] = {'aoe_deg': 15.0, 'aoe_yaw_deg': 14.1, 'tilt_deg': 4.0}
    alone = summarize(ruined, 'tilt_deg')
    assert alone['deploy'] == 'rest bias'
    assert alone['verdict'].startswith("the calibration and the network disagree with the poses' "
                                       'heading more than 2x as much')
    assert summarize(ruined)['deploy'] == 'rest bias'  # judged on the AOE: no guard needed


def test_the_tracking_is_chosen_on_the_judged_figure():
    """Candidates ranked one way by the AOE and the other by the tilt: the key decides."""
    from denoise_imu_ros.evaluation.crossval import _nested, CANDIDATES
    first, second = list(CANDIDATES)[1:3]  # two trackings (the first is none)
    figures = {first: {'aoe_deg': 1.0, 'aoe_yaw_deg': 0.9, 'tilt_deg': 0.5},
               second: {'aoe_deg': 2.0, 'aoe_yaw_deg': 1.9, 'tilt_deg': 0.2}}
    tracked = {n: {label: {m: figures.get(label, {'aoe_deg': 9.0, 'aoe_yaw_deg': 9.0,
                                                  'tilt_deg': 9.0})
                           for m in ('tracker only', 'network', 'calibrated')}
                   for label in CANDIDATES}
               for n in ('a', 'b')}
    raw = {n: {} for n in tracked}
    for key, best in (('aoe_deg', first), ('tilt_deg', second)):
        rows, _, tracking = _nested(raw, tracked, {}, {'a': 0, 'b': 1}, [], key)
        assert tracking['chosen']['network']['label'] == best
        each = {'tracker only': best, 'network': best, 'calibrated': best}
        assert tracking['per_fold'] == {'0': each, '1': each}
        assert tracking['candidates']['network'][best] == figures[best][key]
        assert rows['a']['network'] == figures[best]
    # judged on the tilt, a tracking whose heading is off (yaw over twice the rest bias's)
    # is not chosen however good its tilt
    rest = {n: {'rest bias': {'aoe_deg': 1.0, 'aoe_yaw_deg': 0.5, 'tilt_deg': 0.8}}
            for n in tracked}
    tracking = _nested(rest, tracked, {}, {'a': 0, 'b': 1}, [], 'tilt_deg')[2]
    assert tracking['chosen']['network']['label'] == first  # yaw 0.9 <= 1.0 < 1.9


def test_crossval_of_a_recipe_without_the_heading_chooses_and_reports_on_the_tilt(tmp_path):
    data = tmp_path / 'data'
    for i, bias in enumerate((0.010, 0.012)):
        write_asl(data / f'rec{i}', n_imu=2400, yaw_rate=0.2 + 0.1 * i, gyro_bias=bias)
    recipe = {'dataset': 'synthetic', 'data': str(data), 'sequences': ['rec0', 'rec1'],
              'window': 1024, 'steps': 10, 'val_every': 10, 'restart_period': 10,
              'gyro_std_deg': [1.0, 1.0, 1.0], 'workers': 1, 'heading_weight': 0.0}
    (tmp_path / 'r.yaml').write_text(yaml.safe_dump(recipe))
    report = crossval(tmp_path / 'r.yaml', progress=False)
    assert report['judged_on'] == 'tilt_deg' and 'heading_weight 0' in report['judged_on_why']
    assert report['tracking']['chosen_on'].startswith('the mean tilt error')
    tracking = report['tracking']
    for fold, name in (('0', 'rec0'), ('1', 'rec1')):  # the candidates' figures are tilts
        for m, row in (('network', 'network unblended'), ('calibrated', 'calibrated')):
            label = tracking['per_fold'][fold][m]
            assert tracking['recordings'][name][m][label] == report['recordings'][name][row][
                'tilt_deg'] != report['recordings'][name][row]['aoe_deg']
    printed = crossval_table(report)
    assert 'AOE 3-D / yaw / tilt in degrees' in printed
    assert "Judged on the tilt error alone: the recipe does not trust the poses' heading" \
        in printed
    verdict = parse_meta({'crossval': report}, 'm').crossval
    assert verdict.judged_on == 'tilt_deg'
    assert verdict.mean_deg['network'] == report['mean']['network']['tilt_deg']


def test_attaching_a_report_of_other_recordings_or_a_shorter_training_is_named():
    report = {'folds': [['b'], ['a']], 'steps': 30}
    assert attach_mismatches(report, parse_meta({'train_sequences': ['a', 'b'],
                                                 'train_config': {'steps': 30}}, 'm')) == []
    assert attach_mismatches(report, parse_meta({'train_sequences': ['a', 'c'],
                                                 'train_config': {'steps': 1800}}, 'm')) == [
        "its folds hold out ['a', 'b'], the model was trained on ['a', 'c']",
        'its folds trained 30 steps, the model 1800']


def test_crossval_refuses_to_attach_to_a_model_of_another_training_before_training(
        tmp_path, capsys):
    from helpers import write_untrained_model
    recipe = {'dataset': 'synthetic', 'data': str(tmp_path), 'sequences': ['rec0', 'rec1'],
              'window': 1024, 'steps': 1800}
    (tmp_path / 'r.yaml').write_text(yaml.safe_dump(recipe))
    model = write_untrained_model(tmp_path / 'm.safetensors', {
        'sample_rate_hz': 200.0, 'train_sequences': ['rec0', 'rec1'],
        'train_config': {'steps': 1800}})
    assert main(['crossval', '--recipe', str(tmp_path / 'r.yaml'), '--steps', '30', '--quiet',
                 '--attach', str(model)]) == 1  # the recordings do not even exist: not read
    err = capsys.readouterr().err
    assert 'this cross-validation is not of how that model was trained (its folds trained ' \
        '30 steps, the model 1800)' in err


def test_crossval_command_trains_folds_scores_and_stores_the_report(
        tmp_path, model_file, capsys):
    data = tmp_path / 'data'
    for i, bias in enumerate((0.010, 0.012, 0.011)):  # one z gyro bias per "day"
        write_asl(data / f'rec{i}', n_imu=2400, yaw_rate=0.2 + 0.1 * i, gyro_bias=bias)
    recipe = {'dataset': 'synthetic', 'data': str(data), 'sequences': ['rec0', 'rec1', 'rec2'],
              'window': 1024, 'steps': 12, 'val_every': 4, 'swa_start': 8, 'select': 'swa',
              'restart_period': 12, 'gyro_std_deg': [1.0, 1.0, 1.0], 'workers': 1}
    (tmp_path / 'r.yaml').write_text(yaml.safe_dump(recipe))
    out = tmp_path / 'cv'
    assert main(['crossval', '--recipe', str(tmp_path / 'r.yaml'), '--out', str(out),
                 '--quiet', '--attach', str(model_file)]) == 0
    report = json.loads((out / 'crossval.json').read_text())
    assert list(report['recordings']) == ['rec0', 'rec1', 'rec2']
    assert report['folds'] == [['rec0'], ['rec1'], ['rec2']]
    for name, figures in report['recordings'].items():
        # the bias is a constant of every day: the fitted calibration removes most of it
        assert figures['calibrated']['aoe_deg'] < 0.5 * figures['raw']['aoe_deg']
    for i in range(3):
        trained_on = load_model(out / f'fold{i}' / 'network.safetensors').meta.train_sequences
        assert f'rec{i}' not in trained_on and len(trained_on) == 2
    printed = capsys.readouterr().out
    assert report['verdict'] in printed and 'rec2' in printed
    assert load_model(model_file).meta.crossval.report == report
    # the accelerometer judged on the held-out velocity increments, its verdict stored
    accel = report['accelerometer']
    assert set(accel['recordings']) == {'rec0', 'rec1', 'rec2'}
    assert load_model(model_file).meta.crossval.accel_deploy == accel['deploy']
    assert accel['verdict'] in printed
    # the network's output bias tracking chosen over every held-out recording, stored
    chosen = report['tracking']['chosen']['network']
    stored = load_model(model_file).meta.bias_tracking
    assert (stored is None) == (chosen is None)
    if chosen is not None:
        assert stored == tracking_from_dict(chosen)
        assert stored.sigma_init_deg_s in (stored.sigma_motion_deg_s, 0.5)  # or VQF's start
    assert set(report['tracking']['per_fold']) == {'0', '1', '2'}
    # and its blend with the classical pipeline, which the model file's pipeline then runs
    from denoise_imu_ros.core.modelfile import read_model_file
    from denoise_imu_ros.pipeline.stages import ClassicalMix, correction
    blend = load_model(model_file).meta.blend
    assert blend.weight == report['blend']['chosen']['weight']
    assert (blend.tracking is None) == (report['tracking']['chosen']['tracker only'] is None)
    attached = read_model_file(model_file)
    assert ClassicalMix in {type(s) for s in correction(attached)}
    # folds of one power-on: imu/data's filter is the validation tails' to choose
    assert 'fusion' not in report and 'chosen_on' not in (attached.meta.raw.get('fusion') or {})
    assert ClassicalMix not in {type(s) for s in correction(attached, mix='off')}
    assert main(['eval', '--model', str(model_file), '--data', str(data), '--sequences',
                 'rec0', '--out', str(tmp_path / 'ev'), '--no-plots']) == 0
    assert json.loads((tmp_path / 'ev' / 'results.json').read_text())['crossval'] == report
    assert report['verdict'] in (tmp_path / 'ev' / 'results.md').read_text()
    # a stopped run resumes: the folds already in --out are scored, not trained again;
    # one fold can be trained alone (a process per fold), and the report is the same
    import shutil
    shutil.rmtree(out / 'fold1')
    kept = (out / 'fold0' / 'network.safetensors').stat().st_mtime_ns
    assert main(['crossval', '--recipe', str(tmp_path / 'r.yaml'), '--out', str(out),
                 '--quiet', '--fold', '1']) == 0
    assert (out / 'fold1' / 'calibrated.safetensors').is_file()
    assert main(['crossval', '--recipe', str(tmp_path / 'r.yaml'), '--out', str(out),
                 '--quiet']) == 0
    assert (out / 'fold0' / 'network.safetensors').stat().st_mtime_ns == kept
    assert json.loads((out / 'crossval.json').read_text())['recordings'] == report['recordings']
    # a fold written before a recipe entry existed (unset in this recipe, or at its
    # default: 0.4's files have no accel_input) is this recipe
    from denoise_imu_ros.core.modelfile import add_metadata
    net0 = out / 'fold0' / 'network.safetensors'
    older = load_model(net0).meta.train_config
    assert older.pop('poses', 'absent') is None and older.pop('accel_input') is True
    add_metadata(net0, train_config=older)
    assert main(['crossval', '--recipe', str(tmp_path / 'r.yaml'), '--out', str(out),
                 '--quiet']) == 0
    # models of another recipe are refused, not scored as if this one had made them
    assert main(['crossval', '--recipe', str(tmp_path / 'r.yaml'), '--out', str(out),
                 '--quiet', '--seed', '7']) == 1
    assert 'trained by another recipe' in capsys.readouterr().err


def test_held_out_recordings_are_aligned_like_the_training_ones(tmp_path):
    import dataclasses
    from denoise_imu_ros.data.asl import read_asl
    from denoise_imu_ros.data.bags import write_bag
    from scipy.spatial.transform import Rotation
    marker = Rotation.from_rotvec([30.0, -20.0, 45.0], degrees=True)  # imu_from_pose
    recipe = {'dataset': 'synthetic', 'sequences': ['rec0', 'rec1'], 'window': 1024,
              'steps': 10, 'val_every': 10, 'restart_period': 10, 'workers': 1,
              'gyro_std_deg': [1.0, 1.0, 1.0]}
    for kind in ('plain', 'marker'):
        (tmp_path / kind).mkdir()
    for i, bias in enumerate((0.010, 0.012)):
        rec = read_asl(write_asl(tmp_path / 'plain' / f'rec{i}', n_imu=2400, gyro_bias=bias))
        write_bag(dataclasses.replace(rec, gt_quat=(Rotation.from_quat(rec.gt_quat)
                                                    * marker).as_quat()),
                  tmp_path / 'marker' / f'rec{i}')
    reports = {}
    for kind, align in (('plain', 'none'), ('marker', {
            'time_offset_s': 0.0, 'imu_from_pose_rotation_xyzw': marker.as_quat().tolist()})):
        config = tmp_path / f'{kind}.yaml'
        config.write_text(yaml.safe_dump(dict(recipe, data=str(tmp_path / kind), align=align)))
        reports[kind] = crossval(config, progress=False)['recordings']
    for name, figures in reports['plain'].items():
        for method, scores in figures.items():
            assert reports['marker'][name][method]['aoe_deg'] == pytest.approx(
                scores['aoe_deg'], rel=1e-3, abs=1e-4)


def test_crossval_of_several_seeds_scores_their_ensemble(tmp_path, capsys):
    from denoise_imu_ros.core.metrics import score
    from denoise_imu_ros.data.load import load_sequence
    from denoise_imu_ros.pipeline.rest_bias import track_bias
    from denoise_imu_ros.evaluation.crossval import CANDIDATES
    from denoise_imu_ros.learn.model import correct_gyro, merge
    data = tmp_path / 'data'
    for i, bias in enumerate((0.010, 0.012)):
        write_asl(data / f'rec{i}', n_imu=2400, yaw_rate=0.2 + 0.1 * i, gyro_bias=bias)
    recipe = {'dataset': 'synthetic', 'data': str(data), 'sequences': ['rec0', 'rec1'],
              'window': 1024, 'steps': 10, 'val_every': 10, 'restart_period': 10,
              'gyro_std_deg': [1.0, 1.0, 1.0], 'workers': 1}
    (tmp_path / 'r.yaml').write_text(yaml.safe_dump(recipe))
    out, args = tmp_path / 'cv', ['crossval', '--recipe', str(tmp_path / 'r.yaml'), '--quiet',
                                  '--sessions', 'rec0', 'rec1']  # two power-ons
    # one process per fold trains that fold for every seed listed
    assert main(args + ['--out', str(out), '--fold', '1', '--seeds', '3', '5']) == 0
    assert {p.parent.parent.name for p in out.glob('seed*/fold1/network.safetensors')} == {
        'seed3', 'seed5'}
    assert 'seed3/fold1/, ' in capsys.readouterr().out
    assert main(args + ['--out', str(out), '--seeds', '3', '5']) == 0
    report = json.loads((out / 'crossval.json').read_text())
    assert report['seeds'] == [3, 5] and set(report['per_seed']) == {'3', '5'}
    printed = capsys.readouterr()
    assert 'seed 3 ' in printed.out
    assert 'fold 2/2, seed 5: its models are in' in printed.err  # resumed, not retrained
    seq = load_sequence(data / 'rec0')
    nets = [load_model(out / f'seed{s}' / 'fold0' / 'network.safetensors') for s in (3, 5)]
    assert [n.meta.recipe('seed') for n in nets] == [3, 5]
    assert nets[0].meta.train_sequences == ('rec1',)
    # the ensemble row is what `denoise-imu ensemble` of the fold's two seeds would score,
    # its output's bias tracked as the other fold's held-out recording chose
    tracking = report['tracking']
    for fold, other in (('0', 'rec1'), ('1', 'rec0')):  # chosen on the other fold's recording
        for m in ('network', 'calibrated'):
            figures = tracking['recordings'][other][m]
            assert tracking['per_fold'][fold][m] == min(figures, key=figures.get)
    chosen = CANDIDATES[tracking['per_fold']['0']['network']]

    def tracked(gyro):
        return score(seq, track_bias(gyro, seq.imu[:, 3:], 200.0, chosen))['aoe_deg']
    assert report['recordings']['rec0']['network unblended']['aoe_deg'] == pytest.approx(
        tracked(correct_gyro(merge([n.model for n in nets]), seq.imu)), rel=1e-4)
    for s, net in zip(('3', '5'), nets):
        assert report['per_seed'][s]['recordings']['rec0']['network unblended']['aoe_deg'] == (
            pytest.approx(tracked(correct_gyro(net.model, seq.imu)), rel=1e-6))
    assert report['recordings']['rec0']['network'] != report['per_seed']['3']['recordings'][
        'rec0']['network']
    # the network rows are blended with the tracker-only row at the weight of least ratio
    # to it on the other fold's recording
    blend = report['blend']
    for fold, name, other in (('0', 'rec0', 'rec1'), ('1', 'rec1', 'rec0')):
        bar = report['recordings'][other]['tracker only']['aoe_deg']
        ratios = {float(w): a / bar for w, a in blend['recordings'][other].items()}
        assert blend['per_fold'][fold] == min(ratios, key=ratios.get)
        assert report['recordings'][name]['network']['aoe_deg'] == blend['recordings'][name][
            str(blend['per_fold'][fold])]
    assert set(blend['candidates']) == {str(w) for w in BLEND_WEIGHTS}
    assert 'The network rows blend' in printed.out
    # and, the folds leaving a power-on out, imu/data's filter: each fold's figures at the
    # filter the other fold's recording chose, VQF's defaults on the raw gyro beside
    # its tilt the filter's own or, where lower, that of VQF's defaults on the raw IMU
    fusion = report['fusion']
    for fold, name in (('0', 'rec0'), ('1', 'rec1')):
        rows = fusion['recordings'][name]
        assert rows['network + VQF']['filter'] == fusion['per_fold'][fold]['network']
        assert rows['raw + VQF defaults']['filter'] == 'vqf tau_acc 3 s, bias estimation on'
        if rows['network + VQF']['filter'].endswith(TILT_LABEL):
            assert rows['network + VQF']['tilt_deg'] == pytest.approx(
                rows['raw + VQF defaults']['tilt_deg'], abs=1e-9)
    for row in ('tracker only', 'calibrated', 'network'):
        chosen, tilt = fusion['chosen'][row], fusion['tilt'][row]
        base = chosen['label'].removesuffix(TILT_LABEL)
        assert fusion['candidates'][row][base] == min(fusion['candidates'][row].values())
        assert chosen['classical_tilt'] == (tilt['classical'] < tilt['own']) == (
            base != chosen['label'])
    assert '`imu/data` on the unseen recordings' in printed.out
    assert main(args + ['--seeds', '3', '3']) == 1
    assert '--seeds must list distinct seeds' in capsys.readouterr().err


def test_crossval_under_torchrun_is_a_clear_error_not_a_crash(tmp_path, monkeypatch, capsys):
    """Refuse it before training: torchrun's other processes get no model back from train."""
    for key, value in (('RANK', '1'), ('WORLD_SIZE', '2'), ('MASTER_ADDR', '127.0.0.1'),
                       ('MASTER_PORT', '29500')):
        monkeypatch.setenv(key, value)
    (tmp_path / 'r.yaml').write_text(yaml.safe_dump({
        'dataset': 'synthetic', 'data': str(tmp_path), 'sequences': ['a', 'b']}))
    assert main(['crossval', '--recipe', str(tmp_path / 'r.yaml'), '--quiet']) == 1
    err = capsys.readouterr().err.strip()
    assert 'crossval does not run under torchrun' in err and len(err.splitlines()) == 1


def test_motion_folds_leave_a_session_and_a_motion_kind_out():
    from denoise_imu_ros.evaluation.crossval import motion_folds
    names = ['b_rot', 'b_trans', 'b_fast', 'c_rot', 'c_trans']
    sessions = ['b_rot,b_trans,b_fast', 'c_rot,c_trans']
    pairs = motion_folds(names, sessions, ['b_rot,c_rot', 'b_trans,c_trans,b_fast'])
    assert pairs == [(['b_rot'], ['c_trans']), (['b_trans', 'b_fast'], ['c_rot']),
                     (['c_rot'], ['b_trans', 'b_fast']), (['c_trans'], ['b_rot'])]
    assert sorted(n for held, _ in pairs for n in held) == sorted(names)  # each held out once
    with pytest.raises(TrainingError, match='--motions: b_fast in no motion kind'):
        motion_folds(names, sessions, ['b_rot,c_rot', 'b_trans,c_trans'])
    with pytest.raises(TrainingError, match='holding out b_rot leaves no recording'):
        motion_folds(names, sessions, ['b_rot,c_rot,c_trans', 'b_trans,b_fast'])
    with pytest.raises(TrainingError, match='--motions needs --sessions'):
        crossval('unused.yaml', motions=['a'], sessions=None)


def test_session_folds_leave_one_power_on_out_and_refuse_a_bad_grouping():
    from denoise_imu_ros.evaluation.crossval import session_folds
    names = ['b1', 'b2', 'c1', 'c2', 'c3']
    assert session_folds(names, ['b1,b2', 'c1,c2,c3']) == [['b1', 'b2'], ['c1', 'c2', 'c3']]
    for groups, why in ((['b1,b2', 'c1,c2'], 'c3 in no session'),
                        (['b1,b2,c1', 'c1,c2,c3'], 'c1 in two sessions'),
                        (['b1,b2,x', 'c1,c2,c3'], 'x not in the recipe'),
                        (['b1,b2,c1,c2,c3'], 'fewer than two sessions')):
        with pytest.raises(TrainingError, match=f'--sessions: {why} '):
            session_folds(names, groups)


def test_a_shipped_model_is_never_rewritten_by_an_attach_and_refused_before_any_work(
        tmp_path, capsys):
    import hashlib
    from denoise_imu_ros.core.modelfile import resolve
    shipped = resolve('euroc')
    before = hashlib.sha256(shipped.read_bytes()).hexdigest()
    (tmp_path / 'r.yaml').write_text(yaml.safe_dump({
        'dataset': 'synthetic', 'data': str(tmp_path), 'sequences': ['rec0', 'rec1']}))
    for cmd in (['crossval', '--recipe', str(tmp_path / 'r.yaml'), '--attach', 'euroc'],
                ['tune-fusion', '--model', 'euroc', '--baseline', 'euroc_calibrated',
                 '--data', str(tmp_path / 'absent'), '--attach']):
        assert main(cmd) == 1  # the recordings do not even exist: nothing was read
        err = capsys.readouterr().err.strip()
        assert err.endswith('--attach euroc: a shipped model, shared by every user of this '
                            'install, is never rewritten: copy it and attach to the copy')
        assert len(err.splitlines()) == 1
    assert hashlib.sha256(shipped.read_bytes()).hexdigest() == before


def test_a_verdict_of_another_recipe_or_of_one_fold_is_not_attached(tmp_path, capsys):
    from helpers import write_untrained_model
    recipe = {'dataset': 'synthetic', 'data': str(tmp_path), 'sequences': ['rec0', 'rec1'],
              'window': 1024, 'increments': [16, 32]}
    (tmp_path / 'r.yaml').write_text(yaml.safe_dump(recipe))
    model = write_untrained_model(tmp_path / 'm.safetensors', {
        'sample_rate_hz': 100.0, 'train_sequences': ['rec0', 'rec1'],
        'train_config': {'steps': 1800, 'window': 2048, 'increments': [8, 16], 'seed': 3}})
    assert main(['crossval', '--recipe', str(tmp_path / 'r.yaml'), '--attach',
                 str(model)]) == 1
    assert ('its folds trained another recipe (they differ in increments, window)'
            in capsys.readouterr().err)
    assert main(['crossval', '--recipe', str(tmp_path / 'r.yaml'), '--out', str(tmp_path / 'o'),
                 '--fold', '0', '--attach', str(model)]) == 1
    assert '--attach with --fold: one fold is no verdict' in capsys.readouterr().err
    assert attach_mismatches({'folds': [['rec0'], ['rec1']], 'steps': 1800,
                              'train_config': {'window': 2048, 'increments': [8, 16],
                                               'seed': 0, 'calibration_only': True}},
                             parse_meta({'train_sequences': ['rec0', 'rec1'],
                                         'train_config': {'steps': 1800, 'window': 2048,
                                                          'increments': [8, 16], 'seed': 3}},
                                        'm')) == []


def test_held_out_poses_that_start_after_the_stillness_are_scored_from_the_first_sample(
        tmp_path):
    """A VIO's trajectories, each starting after its still start: the node's turn-on bias."""
    from denoise_imu_ros.core.metrics import score
    from denoise_imu_ros.data.load import load_sequence
    from denoise_imu_ros.pipeline.rest_bias import baseline_gyro
    from helpers import write_late_trajectory
    data, late = tmp_path / 'data', tmp_path / 'vio'
    for i, bias in enumerate((0.010, 0.016)):
        write_late_trajectory(late, write_asl(data / f'rec{i}', n_imu=3000, gyro_bias=bias,
                                              yaw_rate=0.2 + 0.1 * i, still_s=3.0), 4.0)
    recipe = {'dataset': 'synthetic', 'data': str(data), 'sequences': ['rec0', 'rec1'],
              'window': 1024, 'steps': 10, 'val_every': 10, 'restart_period': 10,
              'gyro_std_deg': [1.0, 1.0, 1.0], 'workers': 1, 'rest_bias': True,
              'poses': str(late)}
    (tmp_path / 'r.yaml').write_text(yaml.safe_dump(recipe))
    report = crossval(tmp_path / 'r.yaml', out=tmp_path / 'cv', progress=False)
    net = load_model(tmp_path / 'cv' / 'fold0' / 'network.safetensors')  # rec0 held out
    seq = load_sequence(data / 'rec0', poses=late)
    assert len(seq.lead_in) == 800
    from_stream = score(seq, seq.on_poses(baseline_gyro(net, seq.stream)))['aoe_deg']
    assert report['recordings']['rec0']['rest bias']['aoe_deg'] == pytest.approx(
        from_stream, rel=1e-9)
    # from the poses' start alone, the turn-on bias would be rec1's (the prior)
    assert from_stream < 0.05 < score(seq, baseline_gyro(net, seq.imu))['aoe_deg']


def test_every_tracking_candidate_has_a_twin_started_at_its_sigma_that_a_shaken_start_moves_less():
    """And one at VQF's 0.5 deg/s for a raw gyro, which a drone carried before take-off moves."""
    import dataclasses
    from denoise_imu_ros.evaluation.crossval import TRACKING_GRID
    from helpers import learnt_on_a_shaken_start
    at_sigma = [t for t in TRACKING_GRID if t.sigma_init_deg_s == t.sigma_motion_deg_s]
    assert len(at_sigma) == len(TRACKING_GRID) // 2
    for settings in at_sigma:
        at_half = dataclasses.replace(settings, sigma_init_deg_s=0.5)
        assert at_half in TRACKING_GRID
        assert learnt_on_a_shaken_start(settings) < 0.5 * learnt_on_a_shaken_start(at_half)


@pytest.mark.parametrize('biases, deploy', [
    ([(0.1, -0.05, 0.0)] * 3, 'bias removed'),                     # a constant of the IMU
    ([(0.1, -0.05, 0.0), (-0.1, 0.05, 0.0), (0.0, 0.1, 0.0)], 'as it came'),  # per power-on
])
def test_the_accelerometer_bias_is_removed_only_where_it_carries_to_unseen_recordings(
        tmp_path, biases, deploy):
    from denoise_imu_ros.evaluation.crossval import accel_rows, accel_verdict
    from denoise_imu_ros.evaluation.filters import fit_accel_bias
    from denoise_imu_ros.core.limits import GRAVITY_M_S2
    seqs = [load_sequence(write_asl(tmp_path / f'rec{i}', n_imu=1200, accel=(
        b[0], b[1], GRAVITY_M_S2 + b[2]))) for i, b in enumerate(biases)]
    rows = {}
    for i, seq in enumerate(seqs):  # each held out, the bias fitted on the others
        fitted = fit_accel_bias([s for j, s in enumerate(seqs) if j != i])[0]
        rows[f'rec{i}'] = accel_rows(seq, seq.imu[:, :3], fitted)
        if deploy == 'bias removed':  # the fit is the bias: nothing left
            assert rows[f'rec{i}']['bias removed'] < 1e-3 < rows[f'rec{i}']['as it came']
    report = accel_verdict(rows)
    assert report['deploy'] == deploy and report['window_s'] == 1.0
    assert report['verdict'].endswith('remove it' if deploy == 'bias removed'
                                      else 'the accelerometer as it came')
    # a fold with no fitted bias cannot judge: as it came
    rows['rec0'] = accel_rows(seqs[0], seqs[0].imu[:, :3], None)
    assert list(rows['rec0']) == ['as it came']
    assert accel_verdict(rows)['deploy'] == 'as it came'


def test_a_held_candidate_the_gyro_never_reaches_scores_as_its_unheld_twin_not_run_again(
        tmp_path, monkeypatch):
    import dataclasses
    import math
    from denoise_imu_ros.evaluation import crossval as module
    from denoise_imu_ros.pipeline import rest_bias, stages
    from helpers import write_asl
    seq = load_sequence(write_asl(tmp_path / 'rec', n_imu=2000, yaw_rate=0.5, gyro_bias=0.01))
    slow = seq.stream[:, :3].copy()
    fast = slow + [math.radians(rest_bias.HOLD_ABOVE_DEG_S + 50.0), 0.0, 0.0]  # gravity disagrees
    rows = {'tracker only': slow, 'network': fast}
    none = dict.fromkeys(rows)
    runs = []
    finish = stages.finish
    monkeypatch.setattr(stages, 'finish', lambda *a: runs.append(a[3]) or finish(*a))
    got = module._candidates(seq, rows, seq.rate_hz, seq.stream, none, dict.fromkeys(rows, 1),
                             False)
    held = [label for label, t in module.CANDIDATES.items() if t and t.hold_above_deg_s]
    for label in held:
        twin = module.tracking_label(dataclasses.replace(module.CANDIDATES[label],
                                                         hold_above_deg_s=None))
        assert got[label]['tracker only'] == got[twin]['tracker only']  # never that fast
        assert got[label]['network'] != got[twin]['network']  # held through the spin
        t = module.CANDIDATES[label]
        assert got[label]['network'] == module.score(seq, seq.on_poses(finish(
            fast, seq.stream, seq.rate_hz, t, None, 1, False)))
    # the slow gyro ran each tracking once, the fast one every candidate
    assert len(runs) == (len(module.CANDIDATES) - len(held)) + len(module.CANDIDATES)
