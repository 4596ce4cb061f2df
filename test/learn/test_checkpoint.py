# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Model files: self-describing, pickle-free, and refused clearly when broken."""

import json

from denoise_imu_ros.core.architecture import ModelConfig
from denoise_imu_ros.core.errors import ModelFileError
from denoise_imu_ros.learn.checkpoint import load_model, save_ensemble, save_model
from denoise_imu_ros.learn.model import GyroNet
import numpy as np
import pytest
from safetensors.torch import save_file
import torch


def _model():
    torch.manual_seed(0)
    model = GyroNet(ModelConfig(gyro_std=(0.01, 0.02, 0.03)))
    model.set_normalization(torch.randn(6), torch.rand(6) + 0.5)
    with torch.no_grad():
        model.delta.copy_(0.01 * torch.randn(3, 3))
    return model.eval()


def test_round_trip_rebuilds_the_same_model_from_the_file_alone(tmp_path):
    model = _model()
    save_model(tmp_path / 'm.safetensors', model, {'dataset': 'x', 'sample_rate_hz': 200.0})
    loaded = load_model(tmp_path / 'm.safetensors')
    u = torch.randn(1, 800, 6)
    assert torch.equal(loaded.model(u), model(u))
    assert loaded.meta.sample_rate_hz == 200.0
    assert loaded.meta.raw['receptive_field'] == 511
    assert not loaded.model.training


@pytest.mark.parametrize('calibration_only, deploy, warns', [
    (False, 'network', False), (False, 'calibration', True), (False, 'none', True),
    (True, 'calibration', False), (True, 'network', True), (False, None, False)])
def test_a_model_of_another_kind_than_its_validation_recommends_says_so(
        tmp_path, calibration_only, deploy, warns):
    from denoise_imu_ros.core.modelfile import read_model_file
    from denoise_imu_ros.runtime.advice import deployment_warning
    model = GyroNet(ModelConfig(calibration_only=calibration_only)).eval()
    meta = {'sample_rate_hz': 200.0}
    if deploy:
        meta['crossval'] = {'deploy': deploy, 'verdict': f'... deploy {deploy}'}
    save_model(tmp_path / 'm.safetensors', model, meta)
    warning = deployment_warning(read_model_file(tmp_path / 'm.safetensors'))
    assert (warning is not None) == warns
    if warns:
        kind = 'calibration' if calibration_only else 'network'
        assert warning == (f'm.safetensors is a {kind} model, but the cross-recording '
                           f'validation of its recipe says: ... deploy {deploy}')


def test_the_warning_names_the_figure_the_verdict_compared(tmp_path):
    from denoise_imu_ros.core.modelfile import read_model_file
    from denoise_imu_ros.runtime.advice import deployment_warning
    mean = {'network': {'aoe_deg': 11.5, 'tilt_deg': 3.7},
            'calibrated': {'aoe_deg': 11.3, 'tilt_deg': 3.9}}
    for judged, said in (({}, '11.50° against calibration 11.30° in mean AOE'),
                         ({'judged_on': 'tilt_deg'},
                          '3.70° against calibration 3.90° in mean tilt error')):
        save_model(tmp_path / 'm.safetensors', _model(), {'sample_rate_hz': 200.0, 'crossval': {
            'deploy': 'calibration', 'verdict': 'deploy the calibration', 'mean': mean,
            **judged}})
        assert f'(network {said} on unseen recordings)' in deployment_warning(
            read_model_file(tmp_path / 'm.safetensors'))


def test_corrupt_foreign_and_missing_files_raise_model_file_error(tmp_path):
    good = tmp_path / 'good.safetensors'
    save_model(good, _model(), {})
    data = good.read_bytes()
    (tmp_path / 'trunc.safetensors').write_bytes(data[: len(data) // 2])
    (tmp_path / 'junk.safetensors').write_bytes(b'\x00' * 3)
    torch.save({'a': torch.zeros(1)}, tmp_path / 'pickle.pt')  # a pickle is never loaded
    save_file({'x': torch.zeros(1)}, str(tmp_path / 'foreign.safetensors'))
    cases = {'trunc.safetensors': 'corrupt', 'junk.safetensors': 'not a model file',
             'pickle.pt': 'corrupt', 'foreign.safetensors': 'not a denoise_imu_ros',
             'absent.safetensors': 'no such model file'}
    for name, message in cases.items():
        with pytest.raises(ModelFileError, match=message):
            load_model(tmp_path / name)


def test_other_format_version_and_mismatched_weights_are_refused(tmp_path):
    model = _model()
    tensors = {k: v.contiguous() for k, v in model.state_dict().items()}
    cfg = json.dumps({'calibration_only': False})
    meta = {'format': 'denoise_imu_ros.gyro_model', 'format_version': '99',
            'model_config': cfg}
    save_file(tensors, str(tmp_path / 'v99.safetensors'), metadata=meta)
    with pytest.raises(ModelFileError, match='format version 99, this code reads version 1'):
        load_model(tmp_path / 'v99.safetensors')
    meta['format_version'] = '1'
    del tensors['delta']
    save_file(tensors, str(tmp_path / 'partial.safetensors'), metadata=meta)
    with pytest.raises(ModelFileError, match='inconsistent model file'):
        load_model(tmp_path / 'partial.safetensors')


def test_ensemble_command_writes_one_file_averaging_its_members(model_file, tmp_path):
    from denoise_imu_ros.cli import main
    from denoise_imu_ros.learn.model import correct_gyro
    from helpers import untrained_model
    second = untrained_model()
    with torch.no_grad():
        for p in second.parameters():
            p.add_(0.01 * torch.randn_like(p))
    save_model(tmp_path / 'b.safetensors', second, {
        'dataset': 'test', 'sample_rate_hz': 200.0, 'train_config': {'seed': 7},
        'validation': {'gyro_residual_std': [0.03, 0.02, 0.01]}})
    out = tmp_path / 'ens.safetensors'
    assert main(['ensemble', str(model_file), str(tmp_path / 'b.safetensors'),
                 '--out', str(out)]) == 0
    ens = load_model(out)
    assert ens.model.config.members == 2 and ens.model.receptive_field == 511
    assert [m['seed'] for m in ens.meta.raw['members']] == [None, 7]
    assert ens.meta.validation.gyro_residual_std == pytest.approx([0.02] * 3)
    u = np.random.default_rng(0).normal(0, 1, (800, 6))
    mean = (correct_gyro(load_model(model_file).model, u) + correct_gyro(second, u)) / 2
    np.testing.assert_allclose(correct_gyro(ens.model, u), mean, rtol=0, atol=1e-6)
    # a member normalised otherwise (another run's float32 statistics) is folded in exactly
    other = untrained_model()
    other.set_normalization(torch.tensor([0.1, -0.2, 0.0, 9.5, 0.3, -2.0]),
                            torch.tensor([0.4, 0.2, 0.3, 1.5, 0.8, 1.1]))
    save_model(tmp_path / 'c.safetensors', other, {'sample_rate_hz': 200.0})
    assert main(['ensemble', str(model_file), str(tmp_path / 'c.safetensors'),
                 '--out', str(tmp_path / 'x.safetensors')]) == 0
    mean = (correct_gyro(load_model(model_file).model, u) + correct_gyro(other, u)) / 2
    np.testing.assert_allclose(correct_gyro(load_model(tmp_path / 'x.safetensors').model, u),
                               mean, rtol=0, atol=1e-6)
    # a member without a residual figure: none stored, not a zero in the mean
    assert load_model(tmp_path / 'x.safetensors').meta.raw['validation'] == {}
    # another architecture cannot be averaged in
    save_model(tmp_path / 'd.safetensors', GyroNet(ModelConfig(channels=(8, 16, 32, 64))),
               {'sample_rate_hz': 200.0})
    assert main(['ensemble', str(model_file), str(tmp_path / 'd.safetensors'),
                 '--out', str(tmp_path / 'y.safetensors')]) == 1
    assert not (tmp_path / 'y.safetensors').exists()
    # a calibration or an ensemble as a member: said as such, not as "another architecture"
    save_model(tmp_path / 'cal.safetensors', untrained_model(calibration_only=True),
               {'sample_rate_hz': 200.0})
    for member, said in (('cal.safetensors', 'member 2 is a calibration'),
                         ('ens.safetensors', 'member 2 is an ensemble of 2 already')):
        with pytest.raises(ModelFileError, match=said):
            save_ensemble(tmp_path / 'y.safetensors', [model_file, tmp_path / member])
    # nor a model of another rate (a NaN rate is refused on reading already)
    save_model(tmp_path / 'e.safetensors', untrained_model(), {'sample_rate_hz': 100.0})
    with pytest.raises(ModelFileError, match='trained at different rates: 200.00 Hz, 100.00 Hz$'):
        save_ensemble(tmp_path / 'z.safetensors', [model_file, tmp_path / 'e.safetensors'])
    # members trained on different recordings (fold models): the ensemble names them all
    for name, seqs in (('f1', ['a', 'b']), ('f2', ['b', 'c'])):
        save_model(tmp_path / f'{name}.safetensors', untrained_model(),
                   {'sample_rate_hz': 200.0, 'train_sequences': seqs})
    union = save_ensemble(tmp_path / 'u.safetensors', [tmp_path / 'f1.safetensors',
                                                       tmp_path / 'f2.safetensors'])
    assert union.meta.train_sequences == ('a', 'b', 'c')
    # trainings of two recipes: the file could describe only the first one's
    save_model(tmp_path / 'r1.safetensors', second, {
        'dataset': 'tumvi', 'sample_rate_hz': 200.0, 'train_config': {'seed': 1, 'window': 4000}})
    save_model(tmp_path / 'r2.safetensors', second, {
        'dataset': 'test', 'sample_rate_hz': 200.0, 'train_config': {'seed': 2, 'window': 16000}})
    with pytest.raises(ModelFileError, match='not trainings of one recipe .they differ in '
                                             r'dataset, window\)'):
        save_ensemble(tmp_path / 'r.safetensors', [str(tmp_path / 'r1.safetensors'),
                                                   str(tmp_path / 'r2.safetensors')])


def test_model_files_are_readable_by_everyone(tmp_path):
    save_model(tmp_path / 'm.safetensors', _model().eval(), {})
    assert (tmp_path / 'm.safetensors').stat().st_mode & 0o777 == 0o644


def test_copied_metadata_never_overrides_the_architecture(tmp_path):
    from denoise_imu_ros.learn.model import merge
    single = _model().eval()
    save_model(tmp_path / 'a.safetensors', single, {'sample_rate_hz': 200.0})
    meta = load_model(tmp_path / 'a.safetensors').meta.raw  # holds model_config (members 1)
    save_model(tmp_path / 'b.safetensors', merge([single, single]), meta)
    assert load_model(tmp_path / 'b.safetensors').model.config.members == 2


@pytest.mark.parametrize('meta, message', [
    ({'sample_rate_hz': 'fast'}, "sample_rate_hz 'fast' is not a rate from 0 to"),
    ({'sample_rate_hz': 0}, 'sample_rate_hz 0 is not a rate from 0 to 100000 Hz'),
    ({'sample_rate_hz': 1e20}, 'sample_rate_hz 1e[+]20 is not a rate'),  # no deque of 2e20
    ({'validation': {'gyro_residual_std': ['a', 1, 2]}}, 'gyro_residual_std'),
    ({'validation': [1, 2]}, r'validation \[1, 2\] is not a mapping'),
    ({'validation': {'gyro_residual_std': [0.1, -1, 0]}}, 'is not three non-negative'),
    ({'train_config': 3}, 'train_config 3 is not a mapping'),
])
def test_malformed_metadata_is_refused_on_reading(tmp_path, meta, message):
    save_model(tmp_path / 'm.safetensors', _model().eval(), meta)
    with pytest.raises(ModelFileError, match=message):
        load_model(tmp_path / 'm.safetensors')


def test_a_model_config_that_is_not_a_mapping_or_zero_input_std_is_refused(tmp_path):
    from denoise_imu_ros.core.modelfile import read_model_file, write_model_file
    model = _model().eval()
    arrays = {k: v.numpy() for k, v in model.state_dict().items()}
    write_model_file(tmp_path / 'a.safetensors', model.config, arrays, {})
    from safetensors.numpy import load_file
    from safetensors.numpy import save_file as save_np
    header = {'format': 'denoise_imu_ros.gyro_model', 'format_version': '1',
              'model_config': '[1, 2]'}
    save_np(load_file(str(tmp_path / 'a.safetensors')), str(tmp_path / 'b.safetensors'),
            metadata=header)
    with pytest.raises(ModelFileError, match='inconsistent model file'):
        read_model_file(tmp_path / 'b.safetensors')
    arrays['input_std'][:] = 0
    write_model_file(tmp_path / 'c.safetensors', model.config, arrays, {})
    with pytest.raises(ModelFileError, match='non-positive input_std'):
        read_model_file(tmp_path / 'c.safetensors')


@pytest.mark.parametrize('change, message', [
    ({'dilations': [1, 4, 16, -64]}, 'positive integers'),  # a negative span: heap damage
    ({'kernels': [7, 7, 7, 0]}, 'positive integers'),
    ({'dilations': [1, 4, 16, 10 ** 9]}, 'receptive field'),  # a huge history allocation
    ({'in_channels': 3}, 'in_channels must be 6'),  # crashed at the first sample
    ({'members': 10 ** 6}, 'members must be an integer'),
    ({'channels': [4096, 1], 'kernels': [1, 2], 'dilations': [1, 65535], 'members': 64},
     'the streaming engine would hold'),  # 70 GB of history, from a 14 MB file
    ({'channels': [], 'kernels': [], 'dilations': []}, 'at least one hidden layer'),
])
def test_an_architecture_the_runtime_cannot_run_is_refused_on_reading(
        tmp_path, change, message):
    """Model files are untrusted: their header cannot make the engine write out of bounds."""
    import json
    from denoise_imu_ros.core.modelfile import read_model_file, write_model_file
    from safetensors import safe_open
    from safetensors.numpy import load_file
    from safetensors.numpy import save_file as save_np
    model = _model().eval()
    write_model_file(tmp_path / 'a.safetensors', model.config,
                     {k: v.numpy() for k, v in model.state_dict().items()}, {})
    with safe_open(str(tmp_path / 'a.safetensors'), framework='np') as f:
        header = f.metadata()
    header['model_config'] = json.dumps(dict(json.loads(header['model_config']), **change))
    save_np(load_file(str(tmp_path / 'a.safetensors')), str(tmp_path / 'b.safetensors'),
            metadata=header)
    with pytest.raises(ModelFileError, match=f'inconsistent model file .*{message}'):
        read_model_file(tmp_path / 'b.safetensors')


def test_a_negative_batchnorm_variance_is_refused_on_reading(tmp_path):
    """It passes as finite, and turns every corrected gyro into NaN."""
    from denoise_imu_ros.core.modelfile import read_model_file, write_model_file
    model = _model().eval()
    arrays = {k: v.numpy() for k, v in model.state_dict().items()}
    arrays['net.1.running_var'][0] = -1.0
    write_model_file(tmp_path / 'a.safetensors', model.config, arrays, {})
    with pytest.raises(ModelFileError, match='negative BatchNorm variance'):
        read_model_file(tmp_path / 'a.safetensors')


def test_a_model_trained_on_whole_recordings_has_no_unseen_tail():
    from denoise_imu_ros.core.schema import parse_meta
    from denoise_imu_ros.evaluation.reports import scored_on_training_samples
    cfg = {'window': 16000, 'max_offset': 32}
    head = parse_meta({'train_config': cfg, 'train_sequences': ['a']}, 'm')
    whole = parse_meta({'train_config': dict(cfg, whole_sequences=True),
                        'train_sequences': ['a']}, 'm')
    assert head.training_span == 16032 and whole.training_span is None
    assert scored_on_training_samples(head, ['a'], 16032) == []
    assert scored_on_training_samples(whole, ['a'], 16032) == ['a']


def test_an_ensemble_keeps_its_members_turn_on_bias_settings_or_refuses_two(tmp_path):
    from denoise_imu_ros.pipeline.rest_bias import RestBiasSettings
    from helpers import untrained_model
    paths = []
    for name, prior in (('a', 0.01), ('b', 0.01), ('c', 0.02)):
        paths.append(tmp_path / f'{name}.safetensors')
        save_model(paths[-1], untrained_model(), {'sample_rate_hz': 200.0, 'rest_bias': (
            RestBiasSettings(prior_rad_s=(prior, 0.0, 0.0)).to_dict())})
    ens = save_ensemble(tmp_path / 'ab.safetensors', paths[:2])
    assert ens.meta.rest_bias == RestBiasSettings(prior_rad_s=(0.01, 0.0, 0.0))
    with pytest.raises(ModelFileError, match='remove different turn-on biases'):
        save_ensemble(tmp_path / 'ac.safetensors', [paths[0], paths[2]])
    save_model(tmp_path / 'raw.safetensors', untrained_model(), {'sample_rate_hz': 200.0})
    with pytest.raises(ModelFileError, match='remove different turn-on biases'):
        save_ensemble(tmp_path / 'ar.safetensors', [paths[0], tmp_path / 'raw.safetensors'])


def test_an_ensemble_keeps_the_filter_settings_and_verdict_its_members_share(tmp_path, capsys):
    from denoise_imu_ros.cli import main
    from helpers import untrained_model
    fusion = {'settings': {'tau_acc_s': 5.0, 'bias_estimation': False}}
    verdict = {'deploy': 'network', 'verdict': 'deploy the network'}
    for name, tau in (('a', 5.0), ('b', 5.0), ('c', 3.0)):
        save_model(tmp_path / f'{name}.safetensors', untrained_model(), {
            'sample_rate_hz': 200.0, 'crossval': verdict,
            'fusion': dict(fusion, settings={'tau_acc_s': tau, 'bias_estimation': False})})
    alike = save_ensemble(tmp_path / 'ab.safetensors',
                          [tmp_path / 'a.safetensors', tmp_path / 'b.safetensors'])
    assert alike.meta.raw['fusion'] == fusion and alike.meta.raw['crossval'] == verdict
    assert main(['ensemble', str(tmp_path / 'a.safetensors'), str(tmp_path / 'c.safetensors'),
                 '--out', str(tmp_path / 'ac.safetensors')]) == 0
    differ = load_model(tmp_path / 'ac.safetensors')
    assert 'fusion' not in differ.meta.raw and differ.meta.raw['crossval'] == verdict
    err = capsys.readouterr().err
    assert ("the ensemble has no imu/data's filter settings (its members carry none, or not the "
            'same): tune-fusion --attach stores its own') in err and 'verdict' not in err
