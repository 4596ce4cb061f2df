# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""denoise-imu correct / eval end to end, and one-line errors with exit code 1."""

from pathlib import Path
import re

from denoise_imu_ros.cli import main
from denoise_imu_ros.data.load import load_imu
from denoise_imu_ros.learn.checkpoint import load_model
from denoise_imu_ros.learn.model import correct_gyro
from helpers import SAMPLE
from helpers import write_asl
import numpy as np
import pytest

SAMPLE_DIR = SAMPLE.parent


def _error(capsys):
    """Return the error line, which is one (after any warnings, each a line of its own)."""
    lines = capsys.readouterr().err.strip().splitlines()
    errors = [line for line in lines if not line.startswith(('warning: ', 'note: '))]
    assert len(errors) == 1, lines
    return errors[0]


def test_correct_writes_every_sample_of_a_bag_as_csv(model_file, tmp_path):
    from denoise_imu_ros.core.modelfile import add_metadata
    from denoise_imu_ros.pipeline.fusion import FusionSettings
    bias = (0.02, -0.1, 0.05)  # fitted by tune-fusion: imu/data's and imu/corrected's
    add_metadata(model_file, fusion={'settings': FusionSettings(3.0, False, bias).as_dict()})
    out = tmp_path / 'corrected.csv'
    assert main(['correct', '--model', str(model_file), '--input', str(SAMPLE),
                 '--out', str(out)]) == 0
    lines = out.read_text().splitlines()
    assert lines[0] == 'timestamp_ns,wx,wy,wz,ax,ay,az'
    rec = load_imu(SAMPLE)
    assert len(lines) == len(rec.imu) + 1
    table = np.loadtxt(out, delimiter=',', skiprows=1, dtype=np.float64)
    assert [int(x.split(',')[0]) for x in lines[1:4]] == rec.imu_stamp_ns[:3].tolist()
    expect = correct_gyro(load_model(model_file).model, rec.imu)
    np.testing.assert_allclose(table[:, 1:4], expect, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(table[:, 4:], rec.imu[:, 3:] - bias, rtol=1e-8, atol=1e-9)


def test_a_model_its_validation_advises_against_runs_with_a_warning(tmp_path, capsys):
    assert main(['correct', '--model', 'tumvi', '--input', str(SAMPLE),
                 '--out', str(tmp_path / 'c.csv')]) == 0
    verdict = load_model('tumvi').meta.crossval.verdict
    assert verdict.endswith('deploy no correction')
    advice, mounting = capsys.readouterr().err.splitlines()
    assert advice == (  # its own figure beside the recommended one
        'warning: tumvi.safetensors is a network model, but the cross-recording validation '
        'of its recipe says (network 2.67° against no correction 1.36° in mean AOE on '
        f'unseen recordings): {verdict}')
    # and EuRoC's IMU is not mounted as TUM-VI's: gravity 108 deg from where tumvi had it
    assert mounting.startswith(f"warning: {SAMPLE}: gravity is 108 deg from where the model's "
                               'training IMU had it')


def test_correct_and_process_bag_say_what_the_node_says_of_the_turn_on_bias(tmp_path, capsys):
    for run in (['correct', '--input', str(SAMPLE), '--out', str(tmp_path / 'c.csv')],
                ['process-bag', '--input', str(SAMPLE), '--out', str(tmp_path / 'out')]):
        # EuRoC's 200 Hz against BROAD's 285.7: refused, after the warnings
        assert main([*run, '--model', 'broad_network', '--rest-bias', 'off']) == 1
        assert ('warning: rest_bias off: the model was trained on the gyro less its turn-on '
                'bias, it now gets the raw gyro') in capsys.readouterr().err.splitlines()
    assert main(['correct', '--model', 'euroc', '--rest-bias', 'on', '--input', str(SAMPLE),
                 '--out', str(tmp_path / 'e.csv')]) == 0
    assert 'euroc.safetensors was trained on the raw gyro and stores no turn-on bias' in (
        capsys.readouterr().err)


def test_errors_are_one_line_naming_the_file(model_file, tmp_path, capsys):
    assert main(['correct', '--model', str(tmp_path / 'nope.safetensors'), '--input',
                 str(SAMPLE), '--out', str(tmp_path / 'o.csv')]) == 1
    assert 'nope.safetensors: no such model file' in _error(capsys)
    (tmp_path / 'bad.safetensors').write_bytes(b'garbage' * 10)
    assert main(['correct', '--model', str(tmp_path / 'bad.safetensors'), '--input',
                 str(SAMPLE), '--out', str(tmp_path / 'o.csv')]) == 1
    assert 'bad.safetensors: corrupt' in _error(capsys)
    short = write_asl(tmp_path / 'short', n_imu=400)
    assert main(['correct', '--model', str(model_file), '--input', str(short),
                 '--out', str(tmp_path / 'o.csv')]) == 1
    assert 'short: 400 IMU samples, shorter than the receptive field (511)' in _error(capsys)
    write_asl(tmp_path / 'slow', n_imu=2000, imu_rate=100.0)
    assert main(['eval', '--model', str(model_file), '--data', str(tmp_path), '--sequences',
                 'slow', '--out', str(tmp_path / 'e'), '--no-plots']) == 1
    assert 'IMU rate 100.0 Hz, the model was trained at 200.0 Hz' in _error(capsys)
    assert main(['correct', '--model', str(model_file), '--input', str(SAMPLE),
                 '--imu-topic', '/imu9', '--out', str(tmp_path / 'o.csv')]) == 1
    assert "no topic '/imu9'" in _error(capsys)


def test_one_absurd_imu_row_is_an_error_offline_and_a_counted_drop_in_process_bag(
        model_file, tmp_path, capsys):
    import dataclasses
    from denoise_imu_ros.data.asl import read_asl
    from denoise_imu_ros.data.bags import TYPESTORE, write_bag
    from helpers import break_line, T0
    root = write_asl(tmp_path / 'seq', n_imu=1200)
    break_line(root / 'mav0' / 'imu0' / 'data.csv', 700, f'{T0 + 3_495_000_000},5e38,0,0,0,0,9.8')
    for cmd in (['correct', '--model', str(model_file), '--input', str(root), '--out',
                 str(tmp_path / 'o.csv')],
                ['eval', '--model', str(model_file), '--data', str(tmp_path), '--sequences',
                 'seq', '--out', str(tmp_path / 'e'), '--no-plots']):
        assert main(cmd) == 1
        err = _error(capsys)
        assert 'imu0/data.csv: IMU values out of the physical range' in err
        assert 'in sample 699' in err
    assert not (tmp_path / 'o.csv').exists()
    # a bag holding the same row: process-bag drops and counts it, writes only finite data
    clean = read_asl(write_asl(tmp_path / 'clean', n_imu=1200))
    imu = clean.imu.copy()
    imu[699, 0] = 5e38
    write_bag(dataclasses.replace(clean, imu=imu), tmp_path / 'bad_bag')
    assert main(['process-bag', '--input', str(tmp_path / 'bad_bag'), '--out',
                 str(tmp_path / 'out_bag'),
                 '--model', str(model_file)]) == 0
    assert 'out_of_range 1' in capsys.readouterr().out
    from rosbags.highlevel import AnyReader
    with AnyReader([tmp_path / 'out_bag'], default_typestore=TYPESTORE) as reader:
        conns = [c for c in reader.connections if c.topic == '/imu/corrected']
        values = [reader.deserialize(raw, c.msgtype).angular_velocity
                  for c, _, raw in reader.messages(connections=conns)]
    assert len(values) == 1199
    assert np.isfinite([[v.x, v.y, v.z] for v in values]).all()


def test_garbage_inputs_and_bad_options_are_one_line_errors(model_file, tmp_path, capsys):
    garbage = tmp_path / 'garbage.bag'
    garbage.write_bytes(b'\xff\xfe\x00\x01 not a bag')
    binary = write_asl(tmp_path / 'binary', n_imu=600)
    (binary / 'mav0' / 'imu0' / 'data.csv').write_bytes(b'\xff\xfe\x00\x01binary\n')
    (tmp_path / 'file').write_text('')
    model = ['--model', str(model_file)]
    cases = [
        (['correct', '--input', str(garbage), '--out', str(tmp_path / 'o.csv')] + model,
         'garbage.bag: not a readable bag'),
        (['eval', '--data', str(tmp_path), '--sequences', 'garbage.bag', '--out',
          str(tmp_path / 'e')] + model, 'garbage.bag: not a readable bag'),
        (['process-bag', '--input', str(garbage), '--out', str(tmp_path / 'p')] + model,
         'garbage.bag: cannot read ROS 1 bag'),
        (['play', '--input', str(garbage)], 'garbage.bag: not a readable bag'),
        (['play', '--input', str(SAMPLE), '--topic', 'bad topic'],
         "--topic 'bad topic': Invalid topic"),
        (['correct', '--input', str(binary), '--out', str(tmp_path / 'o.csv')] + model,
         'imu0/data.csv: not a text CSV file'),
        (['eval', '--data', str(SAMPLE.parent), '--sequences', SAMPLE.name,
          '--start-sample', '-100', '--out', str(tmp_path / 'e')] + model,
         '--start-sample -100: must be 0 or more'),
        (['eval', '--data', str(SAMPLE.parent), '--sequences', SAMPLE.name,
          '--out', str(tmp_path / 'file' / 'e')] + model, 'cannot create the output folder'),
        (['correct', '--input', str(SAMPLE), '--out', str(tmp_path / 'file' / 'o.csv')]
         + model, 'cannot write here'),
        (['process-bag', '--input', str(SAMPLE), '--out', str(tmp_path / 'file' / 'p')] + model,
         'cannot write here'),
    ]
    # every numeric option: finite and in range, named before any work
    asl = write_asl(tmp_path / 'asl', n_imu=600)
    for option, value in (('--start', 'nan'), ('--start', '-1'), ('--duration', 'inf'),
                          ('--duration', '0')):
        cases.append((['convert', '--input', str(asl), '--out', str(tmp_path / 'c'), option,
                       value],
                      f'{option} {value}: must be a number'))
    for option, value in (('--rate', 'nan'), ('--rate', '0'), ('--wait', '-1'),
                          ('--wait', 'nan')):
        cases.append((['play', '--input', str(SAMPLE), option, value],
                      f'{option} {value}: must be'))
    cases.append((['train', '--recipe', 'x.yaml', '--seed', '-1'], '--seed -1: must be'))
    recipe = str(Path(__file__).resolve().parents[1] / 'config' / 'train_euroc.yaml')
    # checked by creating a file, before any training: /proc passes a permission test
    cases.append((['train', '--recipe', recipe, '--out', '/proc/m.safetensors'],
                  '/proc: output folder is not writable'))
    cases.append((['crossval', '--recipe', 'x.yaml', '--seeds', '0', '-1'], '--seeds -1: must be'))
    cases.append((['crossval', '--recipe', recipe, '--out', '/proc/cv'],
                  '/proc/cv: cannot create the output folder'))
    for argv, message in cases:
        assert main(argv) == 1, argv
        err = _error(capsys)
        assert message in err, (argv, err)


def test_no_command_writes_over_an_input_or_an_existing_output(model_file, tmp_path, capsys):
    """An existing bag output is refused, a second process-bag before any work."""
    from helpers import crop_bag
    bag = crop_bag(SAMPLE, tmp_path / 'in', 5.0)
    before = {p: p.read_bytes() for p in bag.rglob('*') if p.is_file()}
    inner = next(p for p in before if p.suffix == '.mcap')
    for out in (bag, inner):
        assert main(['correct', '--model', str(model_file), '--input', str(bag), '--out',
                     str(out), '--engine', 'streaming']) == 1
        assert 'is an input of this command' in _error(capsys)
    asl = write_asl(tmp_path / 'asl', n_imu=800)
    csv = asl / 'mav0' / 'imu0' / 'data.csv'
    raw = csv.read_bytes()
    assert main(['correct', '--model', str(model_file), '--input', str(asl), '--out',
                 str(csv), '--overwrite']) == 1  # not even with --overwrite
    assert 'is an input of this command' in _error(capsys) and csv.read_bytes() == raw
    assert main(['ensemble', str(model_file), str(model_file), '--out', str(model_file)]) == 1
    assert 'is an input of this command' in _error(capsys)
    model = model_file.read_bytes()
    assert main(['correct', '--model', str(model_file), '--input', str(asl), '--out',
                 str(model_file), '--overwrite']) == 1  # the model is an input too
    assert 'is an input of this command' in _error(capsys) and model_file.read_bytes() == model
    assert main(['init-recipe', '--data', str(tmp_path), '--sequences', 'asl', '--out',
                 str(csv)]) == 1
    assert 'is an input of this command' in _error(capsys) and csv.read_bytes() == raw
    for command in ('eval', 'noise'):  # reports never land inside a recording
        for out in (asl, asl / 'mav0'):
            assert main([command, '--model', str(model_file), '--data', str(tmp_path),
                         '--sequences', 'asl', '--out', str(out)]) == 1
            assert 'is an input of this command' in _error(capsys)
    assert sorted(p.name for p in asl.rglob('*')) == ['data.csv', 'data.csv', 'imu0', 'mav0',
                                                      'state_groundtruth_estimate0']
    assert all(p.read_bytes() == data for p, data in before.items())
    # an existing output is replaced only when asked
    out = tmp_path / 'c.csv'
    out.write_text('mine\n')
    args = ['correct', '--model', str(model_file), '--input', str(asl), '--out', str(out)]
    assert main(args) == 1 and 'exists already (pass --overwrite' in _error(capsys)
    assert out.read_text() == 'mine\n'
    assert main(args + ['--overwrite']) == 0 and out.read_text().startswith('timestamp_ns')
    folder = tmp_path / 'a_folder'
    folder.mkdir()
    assert main(args[:-1] + [str(folder), '--overwrite']) == 1  # never a folder's content
    assert 'a folder exists there; --overwrite replaces a file, not a folder' in _error(capsys)
    assert folder.is_dir()
    # process-bag twice to one output: the second is refused before it reads anything
    assert main(['process-bag', '--input', str(bag), '--out', str(tmp_path / 'pb'), '--model',
                 str(model_file)]) == 0
    assert main(['process-bag', '--input', str(bag), '--out', str(tmp_path / 'pb'), '--model',
                 str(model_file)]) == 1
    err = _error(capsys)  # it has no --overwrite to suggest
    assert 'exists already' in err and 'remove it' in err and '--overwrite' not in err


def test_an_imu_mounted_unlike_the_models_is_said_in_one_line(tmp_path, capsys):
    import dataclasses
    from denoise_imu_ros.data.bags import write_bag
    from denoise_imu_ros.data.load import load_recording
    from helpers import crop_bag
    from scipy.spatial.transform import Rotation
    head = crop_bag(SAMPLE, tmp_path / 'head', 10.0)
    rec = load_recording(head)
    # the same motion seen by an IMU turned 90 deg about y (EuRoC's x up, now z up)
    turn = Rotation.from_rotvec([0.0, 90.0, 0.0], degrees=True)
    imu = np.hstack([turn.apply(rec.imu[:, :3]), turn.apply(rec.imu[:, 3:])])
    write_bag(dataclasses.replace(rec, imu=imu), tmp_path / 'turned')
    for source, said in ((head, False), (tmp_path / 'turned', True)):
        assert main(['correct', '--model', 'euroc', '--input', str(source), '--out',
                     str(tmp_path / 'out.csv'), '--overwrite']) == 0
        err = capsys.readouterr().err
        turned = re.search(f'warning: {re.escape(str(source))}: gravity is (89|90|91) deg from '
                           "where the model's training IMU had it", err)
        assert bool(turned) == said, err


def test_version_is_the_code_version_a_model_file_records(capsys):
    from denoise_imu_ros.core.modelfile import code_version
    with pytest.raises(SystemExit) as done:
        main(['--version'])
    assert done.value.code == 0
    assert capsys.readouterr().out == f'denoise-imu {code_version()}\n'


def test_the_offline_tools_offer_the_node_s_rest_bias_and_guard_choices():
    """The choices of correct and process-bag are the node's settings and the pipeline's."""
    from denoise_imu_ros.cli import build_parser
    from denoise_imu_ros.pipeline import envelope, rest_bias
    commands = next(a for a in build_parser()._actions if a.choices and 'correct' in a.choices)
    for command in ('correct', 'process-bag'):
        options = {a.dest: a for a in commands.choices[command]._actions}
        assert options['rest_bias'].choices == rest_bias.CHOICES
        assert options['envelope_guard'].choices == envelope.CHOICES
        assert options['rest_bias'].default is options['envelope_guard'].default is None


@pytest.mark.parametrize('signal_error, code, word', [
    (KeyboardInterrupt, 130, 'interrupted'), (None, 143, 'terminated')])
def test_a_signal_while_torch_imports_ends_in_one_line_and_its_exit_code(
        monkeypatch, capsys, signal_error, code, word):
    """Ctrl-C or SIGTERM in the first seconds of train (torch importing) as anywhere else."""
    import builtins

    from denoise_imu_ros.cli import Terminated
    real_import = builtins.__import__

    def slow_torch(name, *args, **kwargs):
        if name == 'torch':
            raise (signal_error or Terminated)()
        return real_import(name, *args, **kwargs)
    monkeypatch.setattr(builtins, '__import__', slow_torch)
    assert main(['train', '--recipe', 'recipe.yaml']) == code
    assert capsys.readouterr().err.strip() == f'denoise-imu train: {word}'


def _commands():
    from denoise_imu_ros.cli import build_parser
    return next(a for a in build_parser()._actions if a.choices and 'correct' in a.choices).choices


def test_one_grammar_input_out_and_topics_only_where_they_act():
    """One recording in is --input, what is written --out; --pose-topic where poses are read."""
    import argparse
    reads_poses = {'check-data', 'init-recipe', 'eval', 'noise', 'convert'}
    for name, parser in _commands().items():
        shown = {o for a in parser._actions if a.help != argparse.SUPPRESS
                 for o in a.option_strings}
        positional = [a.dest for a in parser._actions
                      if not a.option_strings and a.help != argparse.SUPPRESS]
        assert positional in ([], ['models']), name  # ensemble's list of models only
        assert not shown & {'--output', '--config', '--bag'}, name
        assert ('--pose-topic' in shown) == (name in reads_poses), name
        assert f'denoise-imu {name} ' in parser.epilog, name  # an example


def test_the_old_spellings_work_one_release_and_say_so(tmp_path, capsys):
    asl = write_asl(tmp_path / 'asl', n_imu=1200)
    assert main(['convert', str(asl), str(tmp_path / 'bag')]) == 0
    err = capsys.readouterr().err
    assert 'deprecated: the positional ASL_DIR is now --input' in err
    assert 'deprecated: the positional OUT_BAG is now --out' in err
    assert (tmp_path / 'bag').is_dir()
    assert main(['correct', '--model', 'euroc', '--input', str(tmp_path / 'bag'), '--output',
                 str(tmp_path / 'c.csv'), '--engine', 'streaming']) == 0
    assert 'deprecated: --output is now --out' in capsys.readouterr().err
    assert (tmp_path / 'c.csv').is_file()
    # 0.4's order with options between the positionals, and --config
    assert main(['process-bag', str(tmp_path / 'bag'), '--model', 'euroc',
                 str(tmp_path / 'pb')]) == 0
    assert (tmp_path / 'pb').is_dir()
    assert main(['check-data', '--json', str(tmp_path / 'bag')]) in (0, 1)  # judged
    assert 'deprecated: the positional INPUT is now --input' in capsys.readouterr().err
    with pytest.raises(SystemExit) as done:
        main(['process-bag', 'a', 'b', 'c', '--model', 'euroc'])
    assert done.value.code == 2 and 'unrecognized arguments: c' in capsys.readouterr().err


@pytest.mark.parametrize('argv, said', [
    (['process-bag', 'a', '--input', 'b', '--out', 'c', '--model', 'euroc'],
     'the positional INPUT and --input both given'),
    (['process-bag', '--model', 'euroc'], 'required: --input, --out'),
    (['train', '--config', 'a.yaml', '--recipe', 'b.yaml'], '--config and --recipe both given'),
    (['check-data'], 'required: --input')])
def test_a_spelling_missing_or_given_twice_is_a_usage_error(argv, said, capsys):
    with pytest.raises(SystemExit) as done:
        main(argv)
    assert done.value.code == 2
    assert said in capsys.readouterr().err
