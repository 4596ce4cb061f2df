# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
denoise-imu: convert, train, eval and correct from the command line.

Each subcommand's work lives in its own module; this layer only parses arguments and
turns the package's exceptions into a one-line message and exit code 1.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
import signal
import sys
import tempfile
import threading
from typing import Any
import warnings

from .core.errors import DataNote, DataWarning, DenoiseError, OptionError, OutputError

# Commands that run the torch network; the others (process-bag, play, check-data,
# convert, init-recipe, correct --engine streaming) never import torch.
TORCH_COMMANDS = ('train', 'crossval', 'eval', 'ensemble', 'tune-fusion', 'noise')
PYTHON_SHOW_WARNING = warnings.showwarning
NEVER_OVER_A_BAG = 'a bag is never written over: remove it or choose another name'
ALIGN_OPTION = {  # the poses against the IMU's clock and frame, for the scoring tools
    'choices': ('check', 'auto', 'none'), 'default': 'check',
    'help': "check (the default): refuse poses found off the IMU's clock or frame; auto: "
            'move them onto both first (as check-data finds them); none: score them as '
            'they are'}
POSES_OPTION = {  # a VIO's or SLAM's trajectories in place of the recordings' poses
    'metavar': 'DIR', 'help': 'trajectories (TUM format: t x y z qx qy qz qw, as VIO and SLAM '
                              "tools write them; ASL's state CSV), <recording>.txt (.tum, .csv) "
                              "in DIR, in place of the recordings' own poses"}
ESTIMATED_OPTION = {  # a bag's pose topic that is a VIO's or SLAM's, as --poses's files are
    'action': 'store_true',
    'help': "the recordings' own poses (a bag's pose topic, an ASL folder's) are a VIO's or "
            "SLAM's estimate, not motion capture, as trajectory files (--poses) always are"}
# The node's parameters that correct and process-bag take as options (the rest from
# --params-file): parameter -> the option's attribute; their help is the parameter's
OPTION_OF = {'model': 'model', 'rest_bias': 'rest_bias', 'envelope_guard': 'envelope_guard',
             'classical_blend': 'classical_blend', 'fixed_frame': 'fixed_frame',
             'embed_attitude': 'embed_attitude'}
PARAMS_FILE_HELP = ("the node's params YAML (config/gyro_denoiser.yaml, keyed /**:): run as "
                    'the node configured by it; the options given override it')


def _workers(value: str) -> int | str:
    """Parse ``--workers``: a positive count, or auto."""
    if value == 'auto':
        return value
    try:
        count = int(value)
    except ValueError:
        count = 0
    if count < 1:
        raise argparse.ArgumentTypeError(f'{value!r}: a positive number of processes, or auto')
    return count


def _train(args: argparse.Namespace) -> None:
    from .learn.config import load_config
    from .learn.train import train
    cfg = load_config(args.recipe, seed=args.seed, data=args.data, steps=args.steps,
                      calibration_only=True if args.calibration_only else None,
                      whole_sequences=True if args.whole_sequences else None,
                      workers=args.workers, device=args.device)
    inputs = [args.recipe, *(Path(cfg.data) / s for s in cfg.sequences)]
    _guard_output(args.out, inputs, args.overwrite)  # before training, not after
    for folder in (Path(args.out).parent, args.candidates_dir):
        _check_writable(folder)
    result = train(cfg, progress=not args.quiet)
    if result is None:  # one of torchrun's processes other than the first
        return
    try:
        result.save(args.out, args.candidates_dir)
    except OutputError as err:  # a full disk, say: the finished training is not lost
        try:
            kept = Path(tempfile.mkdtemp(prefix='denoise-imu-')) / Path(args.out).name
            result.save(kept)
        except (OSError, OutputError) as again:
            raise OutputError(f'{err}; keeping it in the temporary folder failed too '
                              f'({again}): the trained model is lost') from err
        raise OutputError(f'{err}; the trained model was kept at {kept}') from err
    val = result.meta['validation']
    print(f'saved {args.out}: {result.meta["selected"]} weights (step {val["step"]}), '
          f'validation loss {val["loss"]:.4g}, tail AOE {val["aoe_mean_deg"]:.3f} deg, '
          f'{result.meta["train_seconds"]:.0f} s')


def _guard_output(output: str | Path, inputs: list[str | Path], overwrite: bool,
                  instead: str = 'pass --overwrite to replace it') -> None:
    """
    Apply the one output policy: never over an input, nor over a file unless asked.

    An output that is an input, or lies inside an input folder (an ASL recording's CSV,
    a bag's inner file), is refused whatever ``--overwrite`` says; ``instead`` is what
    the refusal of an existing output suggests (a command without ``--overwrite`` says
    something else).
    """
    _not_an_input(output, inputs)
    if Path(output).exists() and not overwrite:
        raise OutputError(f'{output}: exists already ({instead})')


def _not_an_input(output: str | Path, inputs: list[str | Path]) -> None:
    out = Path(output).resolve()
    for given in inputs:
        inp = Path(given).resolve()
        if out == inp or inp in out.parents:
            raise OutputError(f'{output}: is an input of this command ({given}); refusing to '
                              'write over it')


def _report_inputs(args: argparse.Namespace) -> list[Path]:
    """Return the recordings and model files of eval and noise (their --out spares them)."""
    from .core.modelfile import read_model_file
    models = [read_model_file(m).path for m in (args.model, args.baseline) if m]
    return [*(Path(args.data) / s for s in args.sequences), *models]


def _check_writable(folder: str | Path | None) -> None:
    if folder is None:
        return
    try:
        Path(folder).mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise DenoiseError(f'{folder}: cannot create the output folder ({err.strerror})') from err
    try:  # a real file: permission bits say nothing to root, nor of /proc
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as err:
        raise DenoiseError(f'{folder}: output folder is not writable (a file cannot be '
                           f'created there: {err.strerror})') from err


def _crossval(args: argparse.Namespace) -> None:
    from .core.modelfile import add_metadata, check_attachable, read_model_file
    from .core.schema import CROSSVAL_CHOICE, fusion_metadata
    from .evaluation.crossval import attach_mismatches, crossval
    from .evaluation.reports import crossval_table
    from .learn.config import load_config
    from .runtime.advice import model_kind
    recipe = load_config(args.recipe, seed=args.seed, data=args.data, steps=args.steps)
    if args.attach and args.fold is not None:
        raise OptionError('--attach with --fold: one fold is no verdict; attach when '
                          'crossval scores every fold (without --fold)')
    _check_writable(args.out)  # before the first fold trains, not after
    for path in args.attach or []:  # before the folds train, not after
        check_attachable(path)
        why = attach_mismatches({'folds': [recipe.sequences], 'steps': recipe.steps,
                                 'train_config': recipe.recipe()}, read_model_file(path).meta)
        if why:
            raise DenoiseError(f'--attach {path}: this cross-validation is not of how that '
                               f'model was trained ({"; ".join(why)})')
    report = crossval(args.recipe, args.folds, args.out, progress=not args.quiet,
                      only_fold=args.fold, seeds=args.seeds, sessions=args.sessions,
                      motions=args.motions,
                      seed=args.seed, data=args.data,
                      steps=args.steps, workers=args.workers, device=args.device)
    if report is None:
        where = (f'{args.out}/fold{args.fold}/' if args.seeds is None else ', '.join(
            f'{args.out}/seed{s}/fold{args.fold}/' for s in args.seeds))
        print(f'trained fold {args.fold} into {where}; crossval without --fold scores every '
              'fold (training the missing ones)')
        return
    sys.stdout.write(crossval_table(report))
    for path in args.attach or []:
        model = read_model_file(path)
        row = {'network': 'network', 'calibration': 'calibrated', 'tracker only': 'tracker only'
               }.get(model_kind(model))  # a rest-only model tracks nothing
        tracking = None if row is None else report['tracking']['chosen'][row]
        blend = report['blend']['chosen'] if row == 'network' and 'blend' in report else None
        fusion = None if row is None else fusion_metadata(report, row, model.meta)
        add_metadata(path, crossval=report, bias_tracking=tracking and dict(
            tracking, chosen_on=CROSSVAL_CHOICE + report['tracking']['chosen_on']),
            **({} if blend is None else {'blend': dict(
                blend, chosen_on=CROSSVAL_CHOICE + report['blend']['chosen_on'])}),
            **({} if fusion is None else {'fusion': fusion}))
        print(f'stored the cross-recording figures in {path}' + (
            f', and its output bias tracking ({tracking["label"]})' if tracking else '') + (
            f', and its blend with the classical pipeline (weight {blend["weight"]:g})'
            if blend else '') + (
            f", and imu/data's filter ({report['fusion']['chosen'][row]['label']})"
            if fusion else ''))
        if fusion and report['fusion']['chosen'][row]['accel_bias_removed'] and not any(
                model.meta.fusion.chosen.accel_bias_m_s2):
            print(f'warning: {path}: the folds chose the accelerometer less its training '
                  'bias, but the file holds none (tune-fusion --attach fits it): imu/data '
                  'takes the accelerometer as it came', file=sys.stderr)


def _init_recipe(args: argparse.Namespace) -> None:
    from .learn.recipe import init_recipe, write_recipe
    _guard_output(args.out, [Path(args.data) / s for s in args.sequences], args.overwrite)
    recipe, why = init_recipe(args.data, args.sequences, args.imu_topic, args.pose_topic,
                              args.poses, args.estimated_poses)
    write_recipe(args.out, recipe, why)
    print(f'wrote {args.out}:\n' + ''.join(f'  {line}\n' for line in why), end='')


def _tune_fusion(args: argparse.Namespace) -> None:
    from .core.modelfile import check_attachable, read_model_file
    from .evaluation.filters import attach, table, tune_model
    if args.attach:  # before the work, not after
        for spec in (args.model, args.baseline):
            check_attachable(spec)
    report = tune_model(args.model, args.baseline, args.data, progress=not args.quiet)
    sys.stdout.write(table(report))
    if args.attach:
        replaced = [spec for spec in (args.model, args.baseline)
                    if read_model_file(spec).meta.fusion.by_crossval]
        attach(args.model, args.baseline, report)
        print(f'stored the chosen settings in {args.model} and {args.baseline}')
        for spec in replaced:
            print(f'warning: {spec}: this replaces the filter crossval chose on another '
                  'power-on; crossval --attach after tune-fusion chooses it again',
                  file=sys.stderr)


def _fit_variance(args: argparse.Namespace) -> None:
    from .core.modelfile import add_metadata, check_attachable, read_model_file
    from .evaluation.variance import fit_model
    if args.attach:  # before the work, not after
        check_attachable(args.model)
    reports = fit_model(args.model, args.data, progress=not args.quiet)
    for key, sensor, increments, noise in (
            ('gyro_variance', 'gyro', 'rotation', 'reference_noise_deg'),
            ('accel_variance', 'accelerometer', 'velocity', 'reference_noise_m_s')):
        if key not in reports:
            print(f"{sensor}: no variance fitted (a recording's poses have no positions)")
            continue
        report = reports[key]
        unit = 'deg' if noise.endswith('deg') else 'm/s'
        print(f'{sensor} variance exp(theta . phi), theta '
              f"{[round(t, 3) for t in report['theta']]}, fitted on the "
              f"{report['fitted_on']}; beside it the poses' own noise in every window, "
              f'{report[noise]:.3f} {unit} per axis (not published)')
        print(f'| {increments} increments over | mean NEES, that noise counted (3 if right) | '
              'in 2 sigma (73.9 % if right) | windows |\n|---|---|---|---|')
        for window, row in report['nees'].items():
            print(f"| {window} | {row['mean']:.2f} | {row['in_2_sigma']:.0%} | "
                  f"{row['windows']} |")
        if report['held_out']:
            windows = list(report['nees'])
            print("each recording's tail under the fit on the others' tails, mean NEES (in 2 "
                  f"sigma):\n| recording | {' | '.join(windows)} |\n|---|{'---|' * len(windows)}")
            for name, rows in report['held_out'].items():
                print(f'| {name} | ' + ' | '.join(
                    f"{rows[w]['mean']:.2f} ({rows[w]['in_2_sigma']:.0%})" if w in rows
                    else '-' for w in windows) + ' |')
    if args.attach:
        add_metadata(read_model_file(args.model).path, **{'accel_variance': None, **reports})
        print(f"stored them in {args.model}: imu/corrected carries each message's own "
              'variances')


def _ensemble(args: argparse.Namespace) -> None:
    from .core.modelfile import read_model_file
    from .learn.checkpoint import save_ensemble
    _guard_output(args.out, [read_model_file(m).path for m in args.models], args.overwrite)
    loaded = save_ensemble(args.out, args.models)
    print(f'wrote {args.out}: the mean of {loaded.model.config.members} networks')
    missing = {'fusion': ("imu/data's filter settings", 'tune-fusion --attach'),
               'crossval': ('cross-recording verdict', 'crossval --attach')}
    for key in missing:  # no bias_tracking is a choice crossval makes, not a gap
        if key not in loaded.meta.raw:
            what, how = missing[key]
            print(f'warning: the ensemble has no {what} (its members carry none, or not the '
                  f'same): {how} stores its own', file=sys.stderr)


def _rest_model(args: argparse.Namespace) -> None:
    from .core.modelfile import read_model_file, sample_rate
    from .core.schema import fusion_metadata, TRACKER_ONLY
    from .pipeline.rest_bias import classical_tracking, write_rest_only_model
    like = read_model_file(args.like)
    _guard_output(args.out, [like.path], args.overwrite)
    tracking = classical_tracking(like.meta) if args.tracker_only else None
    fusion = None if tracking is None or like.meta.crossval is None else fusion_metadata(
        like.meta.crossval.report, TRACKER_ONLY, like.meta)  # the classical row's, as chosen
    write_rest_only_model(like, args.out, tracking, fusion)
    tracked = '' if tracking is None else f', its bias tracked ({tracking.describe()})'
    print(f'wrote {args.out}: the gyro less its turn-on bias{tracked}, nothing learnt '
          f'({sample_rate(like):g} Hz, the estimator of {like.path.name})')


def _check_data(args: argparse.Namespace) -> None:
    from .core import jsonio
    from .data.check import check, markdown
    from .data.load import load_recording
    rec = load_recording(args.input, args.imu_topic, args.pose_topic, args.poses)
    report = check(rec, args.max_offset)
    sys.stdout.write(markdown(report))
    if args.json:
        print(jsonio.dumps(report))
    if report['usable'] == 'no':
        raise DenoiseError(f'{args.input}: not usable for training: '
                           + '; '.join(report['reasons']))


def _eval(args: argparse.Namespace) -> None:
    from .evaluation.evaluate import evaluate
    _not_an_input(args.out, _report_inputs(args))  # its reports beside a recording's files
    evaluate(args.model, args.data, args.sequences, args.out, baseline=args.baseline,
             imu_topic=args.imu_topic, pose_topic=args.pose_topic, plots=not args.no_plots,
             start_sample=args.start_sample, align_poses=args.align, poses=args.poses,
             estimated=args.estimated_poses)


def _noise(args: argparse.Namespace) -> None:
    from .evaluation.noise import markdown, noise, yaml_snippet
    _not_an_input(args.out, _report_inputs(args))
    report = noise(args.model, args.data, args.sequences, args.out, baseline=args.baseline,
                   imu_topic=args.imu_topic, pose_topic=args.pose_topic, poses=args.poses,
                   align_poses=args.align)
    sys.stdout.write(markdown(report))
    print(f'\nFor a VIO ({args.out}/noise.yaml; Allan plots and JSON beside it):\n')
    sys.stdout.write(yaml_snippet(report['pooled'], ', '.join(report['recordings']),
                                  report.get('published_density'),
                                  report.get('published_accel_density')))


def _start_up_warnings(model: str, rest: str = 'model', mix: str = 'model') -> None:
    """Say what the node says at start-up of a model run so: its verdict, bias and blend."""
    from .core.modelfile import read_model_file
    from .runtime.advice import blend_warnings, deployment_warning, rest_warnings
    loaded = read_model_file(model)
    for warning in [deployment_warning(loaded), *rest_warnings(loaded, rest),
                    *blend_warnings(loaded, mix)]:
        if warning:
            print(f'warning: {warning}', file=sys.stderr)


def _node_settings(args: argparse.Namespace) -> Any:
    """
    Return the node's settings for an offline run: its params file, then these options.

    What the node would ignore in the file (a parameter it does not have) is said, as the
    node says it; an option given overrides the file, as ``-p`` after ``--params-file``.
    """
    from .runtime.settings import NODE_NAME, Settings
    node = getattr(args, 'namespace', '/').rstrip('/') + NODE_NAME  # as the node is named
    settings, unknown = (Settings.from_params_file(args.params_file, node) if args.params_file
                         else (Settings(), []))
    if unknown:
        print(f'warning: {args.params_file}: ignored parameters the node does not have: '
              f'{", ".join(unknown)}', file=sys.stderr)
    if args.model is None and not args.params_file:
        raise OptionError("give --model, or --params-file: the node's YAML, whose model is "
                          "the node's default (euroc) unless it names one")
    given = {name: getattr(args, option, None) for name, option in OPTION_OF.items()}
    return settings.with_(**{k: v for k, v in given.items() if v is not None})


def _correct(args: argparse.Namespace) -> None:
    from .core.modelfile import read_model_file
    from .evaluation.correct import correct_to_csv
    settings = _node_settings(args)
    rest, guard = settings.choice('rest_bias'), settings.choice('envelope_guard')
    mix = settings.choice('classical_blend')
    model = read_model_file(settings.model)
    _guard_output(args.out, [args.input, model.path], args.overwrite)
    _start_up_warnings(settings.model, rest, mix)
    n = correct_to_csv(settings.model, args.input, args.out, imu_topic=args.imu_topic,
                       engine=args.engine, rest=rest, guard=guard, mix=mix,
                       accel_bias=settings.corrected_accel_bias(model))
    print(f'wrote {n} corrected IMU samples to {args.out}')


def _convert(args: argparse.Namespace) -> None:
    from .data.asl import read_asl
    from .data.bags import IMU_TOPIC, POSE_TOPIC, write_bag
    from .data.timebase import crop, overlap
    _guard_output(args.out, [args.input], False, NEVER_OVER_A_BAG)
    rec = read_asl(args.input)
    rec = crop(overlap(rec) if args.overlap else rec, args.start, args.duration)
    imu_topic, pose_topic = args.imu_topic or IMU_TOPIC, args.pose_topic or POSE_TOPIC
    write_bag(rec, args.out, storage=args.storage, compress=args.compress,
              imu_topic=imu_topic, pose_topic=pose_topic)
    span_s = (rec.imu_stamp_ns[-1] - rec.imu_stamp_ns[0]) * 1e-9
    print(f'wrote {args.out}: {len(rec.imu_stamp_ns)} IMU messages on {imu_topic}, '
          f'{len(rec.gt_stamp_ns)} poses on {pose_topic}, {span_s:.1f} s')


def _process_bag(args: argparse.Namespace) -> None:
    from .core.modelfile import read_model_file
    from .pipeline.online import DROP_CAUSES
    from .runtime.process_bag import process_bag
    settings = _node_settings(args)
    _guard_output(args.out, [args.input, read_model_file(settings.model).path], False,
                  NEVER_OVER_A_BAG)
    _start_up_warnings(settings.model, settings.choice('rest_bias'),
                       settings.choice('classical_blend'))
    counts = process_bag(args.input, args.out, settings, imu_topic=args.imu_topic,
                         storage=args.storage, compress=args.compress,
                         namespace=args.namespace,
                         warn=lambda said: print(f'warning: {said}', file=sys.stderr))
    dropped = ', '.join(f'{k} {v}' for k, v in counts.items() if k in DROP_CAUSES)
    rest = ', '.join(f'{k} {v}' for k, v in counts.items() if k not in DROP_CAUSES)
    print(f'wrote {args.out}: {rest}; dropped: {dropped}')


def _play(args: argparse.Namespace) -> None:
    from .runtime.player import main as play
    play(args.input, args.imu_topic, args.topic, args.rate, args.clock, args.wait)


class _Version(argparse.Action):
    """``--version``: the running code's version, as a model file's ``code_version`` says it."""

    def __init__(self, option_strings: list[str], dest: str, **kwargs: Any) -> None:
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS,
                         help="print the running code's version (a model file records that "
                              'of the code that wrote it) and exit')

    def __call__(self, parser: argparse.ArgumentParser, *args: Any) -> None:
        from .core.modelfile import code_version
        print(f'denoise-imu {code_version()}')
        parser.exit()


def _node_options(p: argparse.ArgumentParser, bag: bool = False) -> None:
    """Add the node's parameters an offline run takes as options, with their own help."""
    from .runtime.settings import Settings
    specs = {name: spec for name, _, spec in Settings.specs()}
    helps = {name: spec.description for name, spec in specs.items()}
    choices = {name: ('model', *('on' if s else 'off' for s in spec.switches))
               for name, spec in specs.items() if spec.switches}
    p.add_argument('--params-file', help=PARAMS_FILE_HELP)
    p.add_argument('--model', help=helps['model'] + ' (required without --params-file)')
    p.add_argument('--rest-bias', choices=choices['rest_bias'], help=helps['rest_bias'])
    p.add_argument('--envelope-guard', choices=choices['envelope_guard'],
                   help=helps['envelope_guard'])
    p.add_argument('--classical-blend', choices=choices['classical_blend'],
                   help=helps['classical_blend'])
    if bag:
        p.add_argument('--fixed-frame', help=helps['fixed_frame'])
        p.add_argument('--embed-attitude', action=argparse.BooleanOptionalAction,
                       help=helps['embed_attitude'])


def build_parser() -> argparse.ArgumentParser:
    """Build the argument parser, its commands in the order a user runs them."""
    from .core.modelfile import MODEL_HELP
    parser = argparse.ArgumentParser(
        prog='denoise-imu', description=__doc__.strip().splitlines()[0],
        formatter_class=lambda prog: argparse.RawDescriptionHelpFormatter(
            prog, max_help_position=24),
        epilog='One recording in is --input; a folder of recordings, --data with '
               '--sequences;\nwhat a command writes, --out. The workflow: check-data, '
               'init-recipe, train,\ncrossval, eval, then correct, process-bag or the '
               "gyro_denoiser node.\n'denoise-imu COMMAND -h': a command's options and "
               'an example.')
    parser.add_argument('--version', action=_Version)
    sub = parser.add_subparsers(dest='command', required=True, metavar='COMMAND')

    def command(name: str, summary: str, example: str) -> argparse.ArgumentParser:
        p = sub.add_parser(name, help=summary, description=summary,
                           epilog=f'example:\n  denoise-imu {name} {example}',
                           formatter_class=argparse.RawDescriptionHelpFormatter)
        p.legacy = []  # the old spellings, read by _settle_spellings
        p.required_group = p.add_argument_group('required')  # checked there too
        return p

    p = command('check-data', 'data quality of one recording: rates, pose holes, label noise',
                '--input ../shared/data/euroc/MH_01_easy')
    _input(p, 'ASL sequence folder or bag with IMU and poses', legacy='input')
    _topics(p, poses=True)
    p.add_argument('--json', action='store_true', help='also print one JSON line at the end')
    p.add_argument('--max-offset', type=float, default=0.5,
                   help='clock-offset search range, +- s (default 0.5)')
    p.add_argument('--poses', metavar='FILE',
                   help='a trajectory file (TUM format, or a folder of <recording>.txt) '
                        "in place of the recording's own poses")
    p.set_defaults(func=_check_data)

    p = command('init-recipe', 'write a training recipe for your recordings from their data',
                '--data my_bags --sequences run1 run2 run3 --out recipe.yaml')
    p.add_argument('--data', required=True, help='folder holding the recordings')
    p.add_argument('--sequences', nargs='+', required=True, help='ASL folders or bags in it')
    p.add_argument('--out', default='recipe.yaml', help='recipe to write')
    _topics(p, poses=True)
    p.add_argument('--overwrite', action='store_true', help='replace an existing --out')
    p.add_argument('--poses', **POSES_OPTION)
    p.add_argument('--estimated-poses', **ESTIMATED_OPTION)
    p.set_defaults(func=_init_recipe)

    p = command('train', 'train a model from a YAML recipe',
                '--recipe config/train_euroc.yaml --out euroc_mine.safetensors')
    _recipe(p, 'e.g. config/train_euroc.yaml')
    p.add_argument('--out', default='model.safetensors', help='model file to write')
    p.add_argument('--seed', type=int, help='overrides the recipe seed')
    p.add_argument('--data', help='overrides the recipe data folder')
    p.add_argument('--steps', type=int, help='overrides the recipe step count')
    p.add_argument('--calibration-only', action='store_true',
                   help='train the 12-parameter "calibrated IMU" baseline')
    p.add_argument('--workers', type=_workers,
                   help='overrides the recipe: data-parallel processes (1 = one process; '
                        'auto: from the cores this machine lends and the recordings)')
    p.add_argument('--device', help='cpu or cuda[:N] (default: cuda when torch sees a GPU)')
    p.add_argument('--whole-sequences', action='store_true',
                   help='draw training windows from the whole sequences, validation tails '
                        'included (validation figures become in-sample)')
    p.add_argument('--candidates-dir', help='also write every candidate model here')
    p.add_argument('--overwrite', action='store_true', help='replace an existing --out')
    p.add_argument('--quiet', action='store_true', help='no progress bar')
    p.set_defaults(func=_train)

    p = command('crossval', 'train leave-recording-out folds of a recipe and score the '
                'held-out recordings: network vs calibrated IMU vs the classical pipeline',
                '--recipe recipe.yaml --seeds 0 1 2 --out folds --attach model.safetensors')
    _recipe(p, 'training recipe (its recordings are split)')
    p.add_argument('--folds', type=int, help='number of folds (default: one per recording)')
    p.add_argument('--sessions', nargs='+', metavar='A,B,..',
                   help='recordings that share a power-on, comma-separated, one argument a '
                        'session: the folds leave one session out (its turn-on bias unseen)')
    p.add_argument('--motions', nargs='+', metavar='A,B,..',
                   help='with --sessions, recordings of one motion kind (rotation, '
                        'translation...), grouped as --sessions: each fold leaves one '
                        "session's recordings of one kind out and trains on the other "
                        "sessions' other kinds (motion and power-on both unseen)")
    p.add_argument('--out', type=Path, help='write the fold models and crossval.json here '
                   '(folds trained there already are scored, not trained again)')
    p.add_argument('--fold', type=int, help='train this fold alone (0-based) into --out, '
                   'e.g. one per process')
    seed = p.add_mutually_exclusive_group()
    seed.add_argument('--seed', type=int, help='overrides the recipe seed')
    seed.add_argument('--seeds', type=int, nargs='+', metavar='SEED',
                      help='train every fold once per seed (into OUT/seed<s>/) and score '
                      'the mean of their corrected gyros: the verdict of the ensemble')
    p.add_argument('--data', help='overrides the recipe data folder')
    p.add_argument('--steps', type=int, help='overrides the recipe step count')
    p.add_argument('--workers', type=_workers, help='overrides the recipe worker count '
                   '(a number or auto)')
    p.add_argument('--device', help='cpu or cuda[:N] (default: cuda when torch sees a GPU)')
    p.add_argument('--attach', nargs='+', metavar='MODEL',
                   help='store the report in these model files (trained with this recipe)')
    p.add_argument('--quiet', action='store_true', help='no progress bar')
    p.set_defaults(func=_crossval)

    p = command('ensemble', 'one model file averaging the outputs of trained models of one '
                'recipe (run in one pass online and offline)',
                'seed0.safetensors seed1.safetensors seed2.safetensors --out model.safetensors')
    p.add_argument('models', nargs='+', help='model files (shipped names or paths)')
    p.add_argument('--out', required=True, help='model file to write')
    p.add_argument('--overwrite', action='store_true', help='replace an existing --out')
    p.set_defaults(func=_ensemble)

    p = command('rest-model', "a model file that only removes the turn-on bias (crossval's "
                "verdict 'rest bias'), or that and tracks the bias left ('tracker only'), "
                'from a model trained with rest_bias',
                '--like broad_network --tracker-only --out tracker_only.safetensors')
    p.add_argument('--like', required=True, help='a model trained with rest_bias: its rate, '
                   'estimator and prior, recordings and verdict')
    p.add_argument('--tracker-only', action='store_true', help='track the bias left too, '
                   'as crossval chose for its tracker-only row (else as the model does)')
    p.add_argument('--out', required=True, help='model file to write')
    p.add_argument('--overwrite', action='store_true', help='replace an existing --out')
    p.set_defaults(func=_rest_model)

    p = command('tune-fusion', "choose the gravity-aided filters' settings on the model's "
                'training recordings (validation tails) and store them',
                '--model model.safetensors --baseline calibrated.safetensors --attach')
    p.add_argument('--model', required=True, help='the network model (shipped name or file)')
    p.add_argument('--baseline', required=True, help='its calibrated-IMU model')
    p.add_argument('--data', help="folder of the training recordings (default: the model's)")
    p.add_argument('--attach', action='store_true',
                   help='store the chosen settings in both model files')
    p.add_argument('--quiet', action='store_true')
    p.set_defaults(func=_tune_fusion)

    p = command('fit-variance', "fit the corrected gyro's and accelerometer's variance per "
                "message to the rotation and velocity increments' errors on the model's "
                'validation tails, and store them',
                '--model model.safetensors --attach')
    p.add_argument('--model', required=True, help='the network model (shipped name or file)')
    p.add_argument('--data', help="folder of the training recordings (default: the model's)")
    p.add_argument('--attach', action='store_true',
                   help='store them in the model file (imu/corrected then carries them)')
    p.add_argument('--quiet', action='store_true')
    p.set_defaults(func=_fit_variance)

    p = command('eval', 'AOE/ROE of raw, calibrated and corrected gyro integration, and of '
                'the classical pipeline',
                '--model euroc --data ../shared/data/euroc --sequences MH_02_easy --out ev')
    p.add_argument('--model', required=True, help=MODEL_HELP)
    p.add_argument('--data', required=True, help='folder holding the sequences')
    p.add_argument('--sequences', nargs='+', required=True, help='ASL folders or bags')
    p.add_argument('--out', required=True, help='output folder (JSON, Markdown, PNG)')
    _topics(p, poses=True)
    p.add_argument('--baseline', help='calibrated-IMU model (default: <dataset>_calibrated '
                   'when shipped)')
    p.add_argument('--start-sample', type=int, default=0,
                   help='score from this sample on (16032: the validation tail of the '
                        'training recipe); the network still sees the samples before')
    p.add_argument('--align', **ALIGN_OPTION)
    p.add_argument('--no-plots', action='store_true')
    p.add_argument('--poses', **POSES_OPTION)
    p.add_argument('--estimated-poses', **ESTIMATED_OPTION)
    p.set_defaults(func=_eval)

    p = command('noise', 'gyro noise figures for a VIO (Allan deviation, Kalibr-style noise '
                'density and random walk) and a check of the covariance',
                '--model euroc --data ../shared/data/euroc --sequences MH_02_easy --out nz')
    p.add_argument('--model', required=True, help=MODEL_HELP)
    p.add_argument('--data', required=True, help='folder holding the recordings')
    p.add_argument('--sequences', nargs='+', required=True, help='recordings with ground truth')
    p.add_argument('--out', required=True, help='output folder (YAML, JSON, PNG)')
    _topics(p, poses=True)
    p.add_argument('--baseline', help='calibrated-IMU model (default: <dataset>_calibrated)')
    p.add_argument('--align', **ALIGN_OPTION)
    p.add_argument('--poses', **POSES_OPTION)
    p.set_defaults(func=_noise)

    p = command('correct', 'write every IMU sample corrected, as imu/corrected carries it, as CSV',
                '--model euroc --input ../shared/data/euroc/MH_02_easy --out MH_02.csv')
    _input(p, 'ASL sequence folder or bag')
    _out(p, 'CSV: timestamp_ns,wx,wy,wz,ax,ay,az (an ASL imu0/data.csv)',
         legacy_option='--output')
    _topics(p, poses=False)
    _node_options(p)
    p.add_argument('--engine', choices=('batch', 'streaming'), default='batch',
                   help='whole-recording torch network, or the per-sample numpy engine')
    p.add_argument('--overwrite', action='store_true', help='replace an existing --out')
    p.set_defaults(func=_correct)

    p = command('process-bag', 'copy a bag and add /imu/corrected, /imu/data and '
                '/imu/attitude (as the node)',
                '--input my_bag --out my_bag_corrected --params-file config/gyro_denoiser.yaml')
    _input(p, 'ROS 1 or ROS 2 bag', legacy='input')
    _out(p, 'ROS 2 bag to write; must not exist', legacy='output')
    _topics(p, poses=False)
    _node_options(p, bag=True)
    p.add_argument('--storage', choices=('mcap', 'sqlite3'), default='mcap',
                   help="the written bag's storage (default: mcap)")
    p.add_argument('--namespace', default='/',
                   help="the node's namespace for the outputs (default /: /imu/corrected, "
                        '/imu/data, /imu/attitude; /denoised: /denoised/imu/corrected, ...)')
    p.add_argument('--compress', action=argparse.BooleanOptionalAction,
                   help='zstd compression (default: as the input bag says it is compressed)')
    p.set_defaults(func=_process_bag)

    p = command('play', "publish a bag's IMU in real time (ros2 bag play stand-in)",
                '--input my_bag --topic imu/data_raw --clock')
    _input(p, 'ROS 1 or ROS 2 bag', legacy='bag')
    _topics(p, poses=False)
    p.add_argument('--topic', default='imu/data_raw',
                   help='topic to publish on (default: %(default)s)')
    p.add_argument('--rate', type=float, default=1.0,
                   help='playback speed factor (default: %(default)s)')
    p.add_argument('--clock', action='store_true', help='also publish /clock')
    p.add_argument('--wait', type=float, default=10.0,
                   help='s to wait for a subscriber before playing (default 10)')
    p.set_defaults(func=_play)

    p = command('convert', 'ASL folder -> ROS 2 bag (IMU + ground-truth pose)',
                '--input ../shared/data/euroc/MH_01_easy --out MH_01_bag')
    _input(p, 'ASL sequence folder', legacy='asl_dir')
    _out(p, 'ROS 2 bag to write; must not exist', legacy='out_bag')
    p.add_argument('--storage', choices=('mcap', 'sqlite3'), default='mcap',
                   help="the written bag's storage (default: mcap)")
    p.add_argument('--start', type=float, default=0.0, help='s after the first IMU sample')
    p.add_argument('--duration', type=float, help='s to keep (default: all)')
    p.add_argument('--compress', action=argparse.BooleanOptionalAction, default=False,
                   help='zstd compression (default: none)')
    p.add_argument('--overlap', action='store_true',
                   help='keep only the span both IMU and ground truth cover')
    p.add_argument('--imu-topic', help='IMU topic to write (default /imu0, as EuRoC)')
    p.add_argument('--pose-topic', help='pose topic to write (default /groundtruth/pose)')
    p.set_defaults(func=_convert)
    return parser


DEPRECATED_IN = '0.6.0'  # the release whose parser drops the old spellings


def _topics(p: argparse.ArgumentParser, poses: bool) -> None:
    """Add the bag topics a command reads: the IMU's, and the poses' where it reads them."""
    p.add_argument('--imu-topic', help='bags: IMU topic (default: the only one)')
    if poses:
        p.add_argument('--pose-topic', help='bags: pose topic (default: the only one)')


def _input(p: argparse.ArgumentParser, what: str, legacy: str | None = None) -> None:
    """Add ``--input``, required; ``legacy``: the positional argument it replaces."""
    p.required_group.add_argument('--input', help=what)
    if legacy:
        _legacy(p, legacy, 'input', f'the positional {legacy.upper()}')


def _out(p: argparse.ArgumentParser, what: str, legacy: str | None = None,
         legacy_option: str | None = None) -> None:
    """Add ``--out``, required; ``legacy``, ``legacy_option``: what it replaces."""
    p.required_group.add_argument('--out', help=what)
    if legacy:
        _legacy(p, legacy, 'out', f'the positional {legacy.upper()}')
    if legacy_option:
        _legacy(p, legacy_option, 'out', legacy_option)


def _recipe(p: argparse.ArgumentParser, what: str) -> None:
    """Add ``--recipe``, required, and ``--config``, its old name."""
    p.required_group.add_argument('--recipe', help=what)
    _legacy(p, '--config', 'recipe', '--config')


def _legacy(p: argparse.ArgumentParser, spelling: str, dest: str, said: str) -> None:
    """Add an old spelling of ``--dest``, kept one release, hidden from the help."""
    own = f'legacy_{dest}_{len(p.legacy)}'
    if spelling.startswith('-'):
        p.add_argument(spelling, dest=own, help=argparse.SUPPRESS)
    else:  # a positional: filled in order, wherever it stands among the options
        p.add_argument(own, nargs='?', metavar=spelling, help=argparse.SUPPRESS)
    p.legacy.append((own, dest, said, not spelling.startswith('-')))


def _settle_spellings(parser: argparse.ArgumentParser, args: argparse.Namespace,
                      extra: list[str]) -> None:
    """
    Take each old spelling as the new one (saying so); then check what is required.

    argparse fills optional positionals at the first positional it meets, so 0.4's
    ``process-bag IN --model M OUT`` leaves OUT over: it goes to the next empty one.
    """
    command = next(a for a in parser._actions
                   if isinstance(a, argparse._SubParsersAction)).choices[args.command]
    for own, _, _, positional in command.legacy:
        if positional and getattr(args, own) is None and extra and \
                not extra[0].startswith('-'):
            setattr(args, own, extra.pop(0))
    if extra:
        command.error(f'unrecognized arguments: {" ".join(extra)}')
    for own, dest, said, _ in command.legacy:
        value = getattr(args, own)
        delattr(args, own)
        if value is None:
            continue
        if getattr(args, dest) is not None:
            command.error(f'{said} and --{dest} both given: give --{dest} only')
        setattr(args, dest, value)
        print(f'denoise-imu {args.command}: deprecated: {said} is now --{dest} (the old '
              f'spelling goes in {DEPRECATED_IN})', file=sys.stderr)
    # argparse's required=True would refuse the old spellings: checked once they are in
    missing = [a.option_strings[0] for a in command.required_group._group_actions
               if getattr(args, a.dest) is None]
    if missing:
        command.error(f'the following arguments are required: {", ".join(missing)}')


# Every numeric option's range, (low, high, low allowed, unit); a value must also be finite.
OPTION_RANGES = {
    'start': (0.0, math.inf, True, ' s'),
    'duration': (0.0, math.inf, False, ' s'),
    'rate': (0.0, math.inf, False, ''),  # playback speed factor
    'wait': (0.0, 3600.0, True, ' s'),
    'max_offset': (0.01, 60.0, True, ' s'),  # the search's own resolution is ms
    'seed': (0, 2**32 - 1, True, ''),  # numpy's and torch's seed range
    'seeds': (0, 2**32 - 1, True, ''),
}


def _check_options(args: argparse.Namespace) -> None:
    for name, (low, high, low_allowed, unit) in OPTION_RANGES.items():
        given = getattr(args, name, None)
        for value in given if isinstance(given, list) else [given]:
            if value is None or (math.isfinite(value) and value <= high
                                 and (low < value or low_allowed and value == low)):
                continue
            bound = f'{low:g}{unit} or more' if low_allowed else f'above {low:g}{unit}'
            limit = '' if high == math.inf else f' and at most {high:g}{unit}'
            raise OptionError(f'--{name.replace("_", "-")} {value:g}: must be a number '
                              f'{bound}{limit}')


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the command is, so that its partial outputs are removed."""


def _on_sigterm(_signum: int, _frame: object) -> None:
    raise Terminated


def _data_warning(message: Warning | str, category: type[Warning], *args: Any,
                  **kwargs: Any) -> None:
    """Say a DataWarning (a DataNote: a note) in one line; leave others to Python's format."""
    if issubclass(category, DataWarning):
        print(f'{"note" if issubclass(category, DataNote) else "warning"}: {message}',
              file=sys.stderr)
    else:
        PYTHON_SHOW_WARNING(message, category, *args, **kwargs)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``denoise-imu`` console script."""
    parser = build_parser()
    args, extra = parser.parse_known_args(argv)
    _settle_spellings(parser, args, extra)
    # play stops on SIGTERM as ros2 bag play does (exit 0); a caller's handler is restored
    own = args.command != 'play' and threading.current_thread() is threading.main_thread()
    before = signal.signal(signal.SIGTERM, _on_sigterm) if own else None
    try:
        with warnings.catch_warnings():  # restores Python's own format afterwards
            warnings.showwarning = _data_warning
            return _run(args)
    finally:
        if own:
            signal.signal(signal.SIGTERM, before)


def _run(args: argparse.Namespace) -> int:
    """Run a parsed command: its errors as one line and an exit code."""
    try:
        if args.command in TORCH_COMMANDS or getattr(args, 'engine', None) == 'batch':
            import torch  # seconds on a loaded machine: Ctrl-C there ends as anywhere
            # Denormal floats in the network's activations slow its CPU convolutions tenfold.
            torch.set_flush_denormal(True)
        _check_options(args)
        args.func(args)
    except DenoiseError as err:
        print(f'denoise-imu {args.command}: error: {err}', file=sys.stderr)
        return 1
    except OSError as err:  # an I/O error no area translated: still one line, path and cause
        where = f'{err.filename}: ' if err.filename else ''
        print(f'denoise-imu {args.command}: error: {where}{err.strerror or err}', file=sys.stderr)
        return 1
    except Terminated:  # a KeyboardInterrupt: training's workers are stopped as for Ctrl-C
        print(f'denoise-imu {args.command}: terminated', file=sys.stderr)
        return 143
    except KeyboardInterrupt:
        print(f'denoise-imu {args.command}: interrupted', file=sys.stderr)
        return 130
    return 0


if __name__ == '__main__':
    sys.exit(main())
