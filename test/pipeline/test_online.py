# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The ROS-free online pipeline: equals offline integration, handles bad stamps."""

from types import SimpleNamespace

from denoise_imu_ros.core.metrics import integrate
from denoise_imu_ros.core.rotation import from_gravity
from denoise_imu_ros.core.schema import parse_meta
from denoise_imu_ros.data.load import load_sequence
from denoise_imu_ros.learn.model import correct_gyro
from denoise_imu_ros.pipeline.online import Drop, DROP_CAUSES, Event, OnlineDenoiser, Output
from denoise_imu_ros.pipeline.streaming import StreamingCorrector
from helpers import SAMPLE, untrained_model
from hypothesis import given, HealthCheck, settings, strategies as st
import numpy as np
import pytest
from scipy.spatial.transform import Rotation
import torch


@pytest.fixture(scope='module')
def seq():
    """Load the bundled real EuRoC sample with ground truth."""
    return load_sequence(SAMPLE)


@pytest.fixture()
def model():
    """Build an untrained eval-mode network."""
    return untrained_model()


def _bare(model, **options):
    """Return the pipeline of a network alone and its attitude."""
    return OnlineDenoiser.of_engine(StreamingCorrector.from_module(model), 200.0, **options)


def _run(denoiser, stamps, imu):
    return [denoiser.process(int(t), row[:3], row[3:]) for t, row in zip(stamps, imu)]


def test_online_attitude_equals_offline_integration_of_the_batch_output(seq, model):
    n = 3000
    outs = _run(_bare(model), seq.stamp_ns[:n], seq.imu[:n])
    gyro = correct_gyro(model, seq.imu[:n])
    np.testing.assert_allclose(np.array([o.gyro for o in outs]), gyro, atol=1e-6)
    # the attitude at stamp k includes sample k's rate: each interval at its ends' mean
    offline = integrate(np.array(from_gravity(*seq.imu[0, 3:])), 0.5 * (gyro[:-1] + gyro[1:]),
                        seq.dt[:n - 1])
    online = Rotation.from_quat(np.array([o.attitude for o in outs]))
    assert np.max((offline.inv() * online).magnitude()) < 1e-6
    assert outs[0].event == Event.START and all(o.event is None for o in outs[1:])
    assert [o.stamp_ns for o in outs] == list(seq.stamp_ns[:n])  # each output has its stamp


def test_with_bias_tracking_online_equals_both_offline_engines(seq, tmp_path):
    """The model file's rest bias, input envelope and output tracking, per sample as offline."""
    from denoise_imu_ros.core.modelfile import read_model_file
    from denoise_imu_ros.pipeline.envelope import excursion
    from denoise_imu_ros.pipeline.rest_bias import RestBiasSettings
    from denoise_imu_ros.evaluation.correct import corrected_gyro
    from denoise_imu_ros.learn.checkpoint import load_model
    from helpers import write_untrained_model
    n = 3000
    gyro_norm, accel_offset = excursion(seq.imu[:n])
    bounds = {'gyro_rad_s': float(np.percentile(gyro_norm, 95)),  # a few excursions
              'accel_offset_m_s2': float(accel_offset.max()) + 1.0}
    mf = read_model_file(write_untrained_model(tmp_path / 'm.safetensors', {
        'sample_rate_hz': 200.0, 'rest_bias': RestBiasSettings().to_dict(),
        'bias_tracking': {'sigma_motion_deg_s': 0.05, 'forgetting_s': 30.0},
        'input_envelope': bounds}))
    denoiser = OnlineDenoiser.from_model_file(mf)
    outs = _run(denoiser, seq.stamp_ns[:n], seq.imu[:n])
    online = np.array([o.gyro for o in outs])
    for engine in ('streaming', 'batch'):
        np.testing.assert_allclose(online, corrected_gyro(mf, seq.imu[:n], engine), atol=1e-6)
    np.testing.assert_allclose(online, load_model(mf.path).correct(seq.imu[:n]), atol=1e-6)
    assert 0 < denoiser.guard.guarded < n  # the envelope held some corrections
    untracked = corrected_gyro(mf, seq.imu[:n], 'streaming', rest='off')
    assert np.abs(online - untracked).max() > 1e-4  # both estimates did something
    off = _run(OnlineDenoiser.from_model_file(mf, rest_choice='off'), seq.stamp_ns[:n],
               seq.imu[:n])
    np.testing.assert_allclose(np.array([o.gyro for o in off]), untracked, atol=1e-6)
    unguarded = _run(OnlineDenoiser.from_model_file(mf, guard_choice='off'), seq.stamp_ns[:n],
                     seq.imu[:n])
    assert np.abs(np.array([o.gyro for o in unguarded]) - online).max() > 1e-4  # it acted
    np.testing.assert_allclose(np.array([o.gyro for o in unguarded]),
                               corrected_gyro(mf, seq.imu[:n], 'streaming', guard='off'),
                               atol=1e-6)


def test_taught_without_the_heading_online_equals_both_offline_engines(seq, tmp_path):
    """The correction about the vertical dropped (after tracking and guard) as offline."""
    from denoise_imu_ros.core.modelfile import read_model_file
    from denoise_imu_ros.pipeline.envelope import excursion
    from denoise_imu_ros.pipeline.rest_bias import RestBiasSettings
    from denoise_imu_ros.evaluation.correct import corrected_gyro
    from helpers import write_untrained_model
    n, cut = 2000, 1200
    gyro_norm, accel_offset = excursion(seq.imu[:n])
    meta = {'sample_rate_hz': 200.0, 'rest_bias': RestBiasSettings().to_dict(),
            'bias_tracking': {'sigma_motion_deg_s': 0.05, 'forgetting_s': 30.0},
            'input_envelope': {'gyro_rad_s': float(np.percentile(gyro_norm, 95)),
                               'accel_offset_m_s2': float(accel_offset.max()) + 1.0}}
    files = {w: read_model_file(write_untrained_model(tmp_path / f'm{w}.safetensors', dict(
        meta, train_config={'heading_weight': w}))) for w in (0.0, 1.0)}
    denoiser = OnlineDenoiser.from_model_file(files[0.0])
    assert denoiser.vertical is not None
    assert OnlineDenoiser.from_model_file(files[1.0]).vertical is None
    # the stream jumps back to its start after `cut` samples: everything restarts
    stamps = np.concatenate([seq.stamp_ns[:cut], seq.stamp_ns[:n - cut]])
    imu = np.concatenate([seq.imu[:cut], seq.imu[:n - cut]])
    outs = _run(denoiser, stamps, imu)
    assert outs[cut].event == Event.TIME_JUMP
    online = np.array([o.gyro for o in outs])
    for engine in ('streaming', 'batch'):
        offline = np.concatenate([corrected_gyro(files[0.0], imu[:cut], engine),
                                  corrected_gyro(files[0.0], imu[cut:], engine)])
        np.testing.assert_allclose(online, offline, atol=1e-6)
    kept = corrected_gyro(files[1.0], imu[:cut], 'streaming')
    assert np.abs(online[:cut] - kept).max() > 1e-4  # the same network, its vertical kept
    assert 0 < denoiser.guard.guarded < n  # the guard acted on some samples too


def test_the_start_attitude_levels_the_accelerometer():
    tilt = Rotation.from_euler('ZYX', [0.0, 0.2, -0.4])
    accel = tilt.inv().apply([0.0, 0.0, 9.81])
    assert (Rotation.from_quat(from_gravity(*accel)).inv() * tilt).magnitude() < 1e-12


def test_the_start_and_reset_tilt_come_from_the_accelerometer_less_its_bias(seq, model):
    bias = (-0.013, 0.122, 0.063)  # EuRoC's fitted one: 0.7 deg of tilt
    den = _bare(model, accel_bias=bias)
    first = _run(den, seq.stamp_ns[:500], seq.imu[:500])[0]
    np.testing.assert_allclose(first.attitude, from_gravity(*(seq.imu[0, 3:] - bias)))
    assert (Rotation.from_quat(first.attitude).inv()
            * Rotation.from_quat(from_gravity(*seq.imu[0, 3:]))).magnitude() > 0.01
    den.reset_attitude()
    out = den.process(int(seq.stamp_ns[500]), seq.imu[500, :3], seq.imu[500, 3:])
    np.testing.assert_allclose(out.attitude, from_gravity(*(seq.imu[500, 3:] - bias)))


def test_bad_stamps_and_values_are_dropped_and_counted(seq, model):
    den = _bare(model)
    t, imu = seq.stamp_ns, seq.imu
    assert isinstance(den.process(int(t[0]), imu[0, :3], imu[0, 3:]), Output)
    bad_gyro = np.array([np.nan, 0.0, 0.0])
    assert den.process(int(t[1]), bad_gyro, imu[1, 3:]) == 'non_finite'
    assert den.process(int(t[1]), imu[1, :3], np.array([0.0, np.inf, 0.0])) == 'non_finite'
    assert den.process(int(t[1]), np.array([5e38, 0.0, 0.0]), imu[1, 3:]) == 'out_of_range'
    assert den.process(int(t[1]), imu[1, :3], np.array([0.0, 0.0, -1e21])) == 'out_of_range'
    assert den.process(0, imu[1, :3], imu[1, 3:]) == 'zero_stamp'
    assert den.process(int(t[0]), imu[1, :3], imu[1, 3:]) == 'duplicate_stamp'
    assert den.process(int(t[0]) - 1000, imu[1, :3], imu[1, 3:]) == 'out_of_order'
    assert isinstance(den.process(int(t[1]), imu[1, :3], imu[1, 3:]), Output)
    assert den.counts == {'non_finite': 2, 'out_of_range': 2, 'zero_stamp': 1,
                          'duplicate_stamp': 1,
                          'out_of_order': 1, 'non_finite_output': 0, 'accepted': 2,
                          'gap_resets': 0,
                          'time_jump_resets': 0, 'skipped_periods': 0,
                          'skipped_input_periods': 0, 'non_finite_covariance': 0}


def test_missing_samples_are_counted_from_the_stamps(seq, model):
    den = _bare(model)
    keep = np.ones(400, bool)
    keep[[10, 11, 12, 200]] = False  # four samples lost upstream
    _run(den, seq.stamp_ns[:400][keep], seq.imu[:400][keep])
    assert den.counts['skipped_periods'] == 4 and den.counts['gap_resets'] == 1


def test_gap_restarts_the_network_and_holds_the_attitude(seq, model):
    den = _bare(model, max_gap_factor=3.0)
    first = _run(den, seq.stamp_ns[:600], seq.imu[:600])
    after = _run(den, seq.stamp_ns[1000:1600], seq.imu[1000:1600])  # 2 s gap
    assert after[0].event == Event.GAP and den.counts['gap_resets'] == 1
    np.testing.assert_array_equal(after[0].attitude, first[-1].attitude)
    # the network restarted exactly as at start-up on the new segment
    np.testing.assert_allclose(np.array([o.gyro for o in after]),
                               correct_gyro(model, seq.imu[1000:1600]), atol=1e-6)


def test_backward_time_jump_resets_everything(seq, model):
    den = _bare(model, time_jump_s=1.0)
    _run(den, seq.stamp_ns[:800], seq.imu[:800])
    again = _run(den, seq.stamp_ns[:300], seq.imu[:300])  # a bag played again
    assert again[0].event == Event.TIME_JUMP and den.counts['time_jump_resets'] == 1
    fresh = _run(_bare(model), seq.stamp_ns[:300],
                 seq.imu[:300])
    np.testing.assert_allclose(again[-1].attitude, fresh[-1].attitude, atol=1e-12)


def test_reset_attitude_reinitialises_from_gravity_at_the_next_sample(seq, model):
    den = _bare(model)
    _run(den, seq.stamp_ns[:500], seq.imu[:500])
    den.reset_attitude()
    out = den.process(int(seq.stamp_ns[500]), seq.imu[500, :3], seq.imu[500, 3:])
    np.testing.assert_allclose(out.attitude, from_gravity(*seq.imu[500, 3:]))


EXTREMES = [1.8e308, -1.8e308, 5e38, 3.4e38, -3e38, 1e30, 1e20, 101.0, 2001.0, np.inf,
            -np.inf, np.nan]
ODD_BUT_VALID = [5e-324, -5e-324, 1e-310, 0.0, -0.0, 99.0, -1999.0]


def test_fuzz_ten_thousand_samples_with_extremes_never_yield_a_non_finite_output(seq, model):
    rng = np.random.default_rng(1)
    den = _bare(model)
    answered = out_of_range = 0
    n = 5000
    for k in range(n):  # a real sample, then one with extreme or odd fields, 1 ms later
        t = int(seq.stamp_ns[k])
        out = den.process(t, seq.imu[k, :3], seq.imu[k, 3:])
        assert isinstance(out, Output) and np.isfinite(out.gyro).all()
        assert np.isfinite(out.attitude).all()
        answered += 1
        sample = seq.imu[k].copy()
        fields = rng.choice(6, size=rng.integers(1, 4), replace=False)
        pool = EXTREMES if rng.random() < 0.7 else ODD_BUT_VALID
        sample[fields] = rng.choice(pool, size=len(fields))
        bad = not (np.isfinite(sample).all() and np.abs(sample[:3]).max() <= 100
                   and np.abs(sample[3:]).max() <= 2000)
        out = den.process(t + 1_000_000, sample[:3], sample[3:])
        if bad:
            assert out in ('non_finite', 'out_of_range')
            out_of_range += out == 'out_of_range'
        else:
            assert isinstance(out, Output) and np.isfinite(out.gyro).all()
    assert answered == n and out_of_range > 1000
    assert den.counts['non_finite'] + den.counts['out_of_range'] > 0.6 * n


# Every float64 (NaN, +-inf, +-1.8e308, denormals, +-0.0 included) in every field, and
# stamp steps that repeat, go back, jump forward or are normal.
FIELDS = st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64),
                  min_size=6, max_size=6)
STEPS = st.sampled_from([5_000_000] * 6 + [0, -3_000_000, 40_000_000, -2_000_000_000])
STREAMS = st.lists(st.tuples(STEPS, st.one_of(FIELDS, st.just(None))), min_size=20,
                   max_size=60)


@pytest.fixture()
def denormals():
    """
    Let the CPU keep denormal floats, which hypothesis needs to draw subnormals.

    Training and the CLI, run earlier in the same pytest process, switch on flush-to-zero.
    """
    torch.set_flush_denormal(False)


@settings(max_examples=300, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(stream=STREAMS)
def test_property_no_sample_raises_or_yields_a_non_finite_output(
        denormals, seq, model, stream):
    den = _bare(model)
    t = 1_700_000_000 * 10**9
    for k, (step, fields) in enumerate(stream):
        t += step
        sample = seq.imu[k] if fields is None else np.array(fields)  # None: a real sample
        out = den.process(t, sample[:3], sample[3:])
        if isinstance(out, Output):
            assert np.isfinite(out.gyro).all() and np.isfinite(out.attitude).all()
            assert abs(np.linalg.norm(out.attitude) - 1) < 1e-9
    counted = den.counts['accepted'] + sum(den.counts[c] for c in DROP_CAUSES)
    assert counted == len(stream)  # every sample accepted or dropped with a cause


def test_a_second_clock_and_a_rate_change_are_told_from_losses(seq, model):
    """No 1.6e14 skipped periods; an off-rate stream is caught at once."""
    den = _bare(model)
    imu = seq.imu
    t = 10**9
    den.process(t, imu[0, :3], imu[0, 3:])
    out = den.process(t + 10**15, imu[1, :3], imu[1, 3:])  # another publisher's clock
    assert out.event == Event.TIME_JUMP and den.counts['skipped_periods'] == 0
    t += 10**15
    flags = []
    for k in range(1, 30):  # 100 Hz into the 200 Hz model
        den.process(t + k * 10_000_000, imu[k, :3], imu[k, 3:])
        flags.append(den.rate_suspect)
    assert flags.index(True) == 9 and all(flags[9:])
    t += 29 * 10_000_000
    den.process(t + 5_000_000, imu[30, :3], imu[30, 3:])  # on time again
    assert not den.rate_suspect


def test_a_stream_slower_than_the_gap_limit_is_off_rate_too(seq, model):
    """50 Hz into the 200 Hz model: every interval is a gap, and the stream is suspect."""
    den = _bare(model)
    flags = [den.process(10**9 + k * 20_000_000, seq.imu[k, :3], seq.imu[k, 3:]).rate_suspect
             for k in range(30)]
    assert den.counts['gap_resets'] == 29
    assert flags.index(True) == 10 and all(flags[10:])


def test_a_stream_whose_median_rate_is_off_is_suspect_though_no_run_of_intervals_is(seq, model):
    """Intervals of 1 and 2.5 periods in turn: each on-time one ends a run, the median not."""
    den = _bare(model)
    t, flags = 10**9, []
    for k in range(100):
        t += 5_000_000 if k % 2 else 12_500_000
        flags.append(den.process(t, seq.imu[k, :3], seq.imu[k, 3:]).rate_suspect)
    assert den.input_rate_hz == pytest.approx(1e9 / 8_750_000)  # the median of 1 and 2.5
    assert flags.index(True) == 32 and all(flags[32:])  # from the first full window
    for k in range(100, 140):  # on rate again: clear at the next full window
        t += 5_000_000
        flags.append(den.process(t, seq.imu[k, :3], seq.imu[k, 3:]).rate_suspect)
    assert not flags[-1] and den.input_rate_hz == pytest.approx(200.0)


def test_losses_of_a_stream_faster_than_the_model_are_counted(seq, model):
    """1 kHz into the 200 Hz model, every fifth message lost."""
    den = _bare(model)
    kept = [k for k in range(2000) if k % 5 != 4]
    for k in kept:
        den.process(10**9 + k * 1_000_000, seq.imu[k % 500, :3], seq.imu[k % 500, 3:])
    # every loss after the first window of intervals (the stream's own period) and before
    # the last sample (a loss shows when the next sample comes) is counted
    assert den.counts['skipped_input_periods'] == sum(1 for k in range(41, 1999)
                                                      if k % 5 == 4)
    assert den.counts['skipped_periods'] == 0  # in periods of the model's rate: none


def test_a_correction_that_is_not_finite_is_dropped_never_output(tmp_path, seq):
    """Finite weights can still overflow float32: such a sample is counted, not published."""
    from denoise_imu_ros.core.modelfile import read_model_file
    from helpers import write_untrained_model
    path = write_untrained_model(tmp_path / 'm.safetensors', {'sample_rate_hz': 200.0})
    loaded = read_model_file(path)
    loaded.arrays['net.0.weight'][:] = 3e38  # finite, and its products overflow
    den = OnlineDenoiser.from_model_file(loaded)
    outs = [den.process(10**9 + k * 5_000_000, seq.imu[k, :3], seq.imu[k, 3:])
            for k in range(20)]
    assert outs == ['non_finite_output'] * 20 and den.counts['accepted'] == 0
    assert den.counts['non_finite_output'] == 20


def test_integer_and_float32_samples_are_read_as_float64(model):
    """A driver's int16 counts or float32 values: the same corrections as in float64."""
    gyro32 = np.array([0.01, -0.02, 0.03], np.float32)
    accel = np.array([0, 0, 10], np.int16)
    first, second = _bare(model), _bare(model)
    for k in range(5):
        a = first.process(10**9 + k * 5_000_000, gyro32, accel)
        b = second.process(10**9 + k * 5_000_000, gyro32.astype(float), accel.astype(float))
        assert np.array_equal(a.gyro, b.gyro) and np.array_equal(a.attitude, b.attitude)


def test_with_a_rest_bias_the_model_sees_what_the_batch_path_feeds_it(seq, model):
    from denoise_imu_ros.pipeline.rest_bias import (rest_bias_batch, RestBiasSettings,
                                                    remove_rest_bias)
    from denoise_imu_ros.pipeline.stages import (Attitude, model_input, Network, Pipeline,
                                                 TurnOnBias)
    n, settings = 3000, RestBiasSettings(prior_rad_s=(0.002, -0.01, 0.03))
    den = OnlineDenoiser(Pipeline([Network(StreamingCorrector.from_module(model)),
                                   TurnOnBias(settings, 200.0), Attitude()]), 200.0)
    outs = _run(den, seq.stamp_ns[:n], seq.imu[:n])
    fed = remove_rest_bias(seq.imu[:n], 200.0, settings)
    meta = parse_meta({'sample_rate_hz': 200.0, 'rest_bias': settings.to_dict()}, 'm')
    assert np.array_equal(model_input(SimpleNamespace(meta=meta, path='m'), seq.imu[:n]), fed)
    assert not np.array_equal(fed, seq.imu[:n])
    np.testing.assert_allclose(np.array([o.gyro for o in outs]), correct_gyro(model, fed),
                               atol=1e-6)
    # a gap is the same run: the estimate goes on over both stretches
    later = _run(den, seq.stamp_ns[n + 1000:n + 1100], seq.imu[n + 1000:n + 1100])
    both = rest_bias_batch(np.vstack([seq.imu[:n], seq.imu[n + 1000:n + 1100]]), 200.0,
                           settings)
    assert later[0].event == Event.GAP
    np.testing.assert_array_equal(den.rest.estimate()[0], both['bias'][-1])


def test_a_clock_stepped_back_keeps_the_turn_on_bias_found(model):
    """An NTP step or a bag replayed is the same power-on: not the prior again in motion."""
    from denoise_imu_ros.pipeline.rest_bias import RestBiasSettings
    from denoise_imu_ros.pipeline.stages import Attitude, Network, Pipeline, TurnOnBias
    rng, bias = np.random.default_rng(3), np.array([0.01, -0.02, 0.015])
    den = OnlineDenoiser(Pipeline([TurnOnBias(RestBiasSettings(), 200.0), Attitude(),
                                   Network(StreamingCorrector.from_module(model))]), 200.0)
    stamps = 10**9 + np.arange(1000) * 5_000_000
    still = np.hstack([bias + 1e-4 * rng.normal(size=(1000, 3)),
                       np.tile([0.0, 0.0, 9.81], (1000, 1))])
    _run(den, stamps, still)
    found = den.rest.estimate()
    np.testing.assert_allclose(found[0], bias, atol=1e-3)  # 5 s still: the bias found
    turning = still.copy()
    turning[:, :3] += np.outer(np.sin(np.arange(1000) / 50), [0.3, -0.5, 0.8])
    replay = _run(den, stamps[:600], turning[:600])  # the clock steps back 5 s, in motion
    assert replay[0].event == Event.TIME_JUMP
    np.testing.assert_array_equal(den.rest.estimate()[0], found[0])  # no stillness since
    # a new power-on after all (the clock stepped back again): its stillness moves it as
    # fast as a start moves the prior
    other = still.copy()
    other[:, :3] += [0.02, 0.01, -0.02]
    assert _run(den, stamps[:300], other[:300])[0].event == Event.TIME_JUMP
    fresh = OnlineDenoiser(Pipeline([TurnOnBias(RestBiasSettings(), 200.0), Attitude(),
                                     Network(StreamingCorrector.from_module(model))]), 200.0)
    _run(fresh, stamps[:300], other[:300])
    kept_error = np.abs(den.rest.estimate()[0] - (bias + [0.02, 0.01, -0.02])).max()
    fresh_error = np.abs(fresh.rest.estimate()[0] - (bias + [0.02, 0.01, -0.02])).max()
    assert kept_error <= 2 * fresh_error + 1e-3


def test_a_dropped_non_finite_output_still_counts_its_input_for_the_guard():
    """The engine stepped on it: its motion is in the receptive field that follows."""
    from denoise_imu_ros.core.schema import InputEnvelope
    from denoise_imu_ros.pipeline.envelope import Guard
    from denoise_imu_ros.pipeline.stages import (Attitude, EnvelopeApply, EnvelopeCheck, Network,
                                                 Pipeline)

    class Broken:  # a model whose output is non-finite beyond 1 rad/s
        receptive_field = 5

        def reset(self) -> None:
            pass

        def step(self, fed: np.ndarray) -> np.ndarray:
            gyro = fed[:3].copy()
            return gyro * np.nan if np.linalg.norm(gyro) > 1.0 else gyro + 0.5

    guard = Guard(InputEnvelope(1.0, 50.0, (0.01, 0.0, 0.0)), 5, 200.0)
    den = OnlineDenoiser(Pipeline([Network(Broken()), EnvelopeCheck(guard, 200.0),
                                   EnvelopeApply(guard), Attitude()]), 200.0)
    gyro = np.full((12, 3), 0.1)
    gyro[3] = [2.0, 0.0, 0.0]
    accel = np.array([0.0, 0.0, 9.81])
    outs = [den.process(1_000_000_000 + k * 5_000_000, g, accel) for k, g in enumerate(gyro)]
    assert outs[3] is Drop.NON_FINITE_OUTPUT and den.counts['non_finite_output'] == 1
    published = {k: o.gyro for k, o in enumerate(outs) if isinstance(o, Output)}
    for k in (4, 5, 6, 7):  # sample 3 is within their receptive field: the fallback
        np.testing.assert_allclose(published[k], gyro[k] + [0.01, 0.0, 0.0])
    for k in (0, 1, 2, 8, 9):  # outside it: the model's output
        np.testing.assert_allclose(published[k], gyro[k] + 0.5)
