# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The stage table: one order, one reset matrix, per sample equal to over arrays."""

import dataclasses
import re

from denoise_imu_ros.core.modelfile import read_model_file
from denoise_imu_ros.core.schema import Blend, RestBiasSettings, SampleVariance
from denoise_imu_ros.data.load import load_imu
from denoise_imu_ros.pipeline import envelope, stages
from denoise_imu_ros.pipeline.blend import Blender
from denoise_imu_ros.pipeline.online import OnlineDenoiser
from denoise_imu_ros.pipeline.stages import (Attitude, ClassicalMix, correction, EnvelopeApply,
                                             EnvelopeCheck, Event, Flow, Orientation, Pipeline,
                                             STAGES, TurnOnBias, VarianceStage, VerticalDrop)
from helpers import DATA
import numpy as np
import pytest

TRIAL = DATA / 'broad' / '07_undisturbed_fast_rotation_B'
PART = slice(30500, 34500)  # where it turns faster than broad_network's envelope


@pytest.fixture(scope='module')
def recording():
    if not TRIAL.exists():
        pytest.skip(f'{TRIAL} is not here')
    rec = load_imu(TRIAL)
    return rec.imu_stamp_ns[PART], rec.imu[PART]


def test_every_stage_per_sample_equals_the_same_stage_over_arrays(recording):
    """
    broad_network has every stage (the vertical drop and a variance added): node and eval agree.

    Bit for bit, the variance to rounding (running sums). With the guard, and the blend's
    fallback to the classical pipeline (at a bound that half the samples exceed), acting on
    part of it.
    """
    stamps, imu = recording
    model = read_model_file('broad_network')
    rate, field = model.meta.sample_rate_hz, model.config.receptive_field
    fusion = dataclasses.replace(model.meta.fusion.chosen, classical_tilt=True)  # the raw too
    held = float(np.median(envelope.sustained(imu, round(rate))))  # half of it beyond
    bounds = dataclasses.replace(model.meta.input_envelope, sustained_accel_m_s2=held)

    def every_stage():
        guard = envelope.Guard(bounds, field, rate, hold_beyond=True)
        mix = ClassicalMix(Blender(Blend(0.6, model.meta.bias_tracking), rate))
        return Pipeline([*correction(model, guard='off', mix='off'), EnvelopeCheck(guard, rate),
                         EnvelopeApply(guard), mix, VerticalDrop(rate),
                         VarianceStage(SampleVariance((-7.5, 1.5, 2.0, -1.5)), rate),
                         Attitude(fusion.accel_bias_m_s2), Orientation(rate, fusion)])
    online = OnlineDenoiser(every_stage(), rate)
    assert [type(s) for s in online.pipeline.stages] == [kind for kind, _ in STAGES]
    outs = [online.process(int(t), row[:3], row[3:]) for t, row in zip(stamps, imu)]
    assert online.counts['accepted'] == len(imu) and online.guard.guarded > 0  # the guard acted
    assert 0 < online.pipeline.get(ClassicalMix).blender.classical_only < len(imu)
    batch = every_stage().run(Flow.recording(imu, stamps, rate))
    np.testing.assert_array_equal(np.array([o.gyro for o in outs]), batch.out)
    np.testing.assert_array_equal(np.array([o.attitude for o in outs]), batch.attitude)
    np.testing.assert_array_equal(np.array([o.orientation for o in outs]), batch.orientation)
    np.testing.assert_allclose([o.gyro_var for o in outs], batch.variance, rtol=1e-9)


def test_the_batch_path_is_the_table_up_to_and_after_the_network(recording):
    """model_input is the stages before the network; finish those after it."""
    stamps, imu = recording
    model = read_model_file('broad_network')
    whole = stages.corrected(model, imu)
    fed = stages.model_input(model, imu)
    np.testing.assert_array_equal(fed, Pipeline(correction(model)).run(
        Flow.recording(imu), before=stages.Network).fed)
    network = correction(model)[0].engine.process(fed)
    field = model.config.receptive_field
    np.testing.assert_array_equal(whole, stages.finish(
        network, fed, model.meta.sample_rate_hz, model.meta.bias_tracking,
        model.meta.input_envelope, field, blend=model.meta.blend))


def test_a_pipeline_runs_its_stages_in_the_table_order_whatever_order_given():
    rate = 200.0
    given = [Attitude(), VerticalDrop(rate), TurnOnBias(RestBiasSettings(), rate)]
    assert [type(s) for s in Pipeline(given).stages] == [TurnOnBias, VerticalDrop, Attitude]

    class Extra(stages.Stage):

        def step(self, flow):
            pass
    with pytest.raises(TypeError, match='not a stage of the table'):
        Pipeline([Extra()])
    with pytest.raises(TypeError, match='two stages of one kind'):
        Pipeline([Attitude(), Attitude()])


def test_the_table_in_the_docstring_is_the_table_the_code_runs():
    """Each row's 'reset by' column names exactly the events STAGES resets it at."""
    words = {'start': Event.START, 'gap': Event.GAP, 'jump': Event.TIME_JUMP,
             'request': Event.REQUESTED}
    rows = [line for line in stages.__doc__.splitlines()
            if line and not line.startswith('=') and '  ' in line][1:]  # after the header
    assert len(rows) == len(STAGES)
    for row, (kind, resets) in zip(rows, STAGES):
        named = {words[w] for w in re.findall(r'\b(start|gap|jump|request)\b',
                                              row.split('  ')[-1])}
        assert named == set(resets), (row, kind.__name__)


def test_the_envelope_holds_the_tracker_beyond_the_sustained_bound_only_where_blended():
    """Blended, the classical output is given there; unblended, the tracker follows the model's."""
    model = read_model_file('broad_network')

    def guard(**options):
        return Pipeline(correction(model, **options)).get(EnvelopeCheck).guard
    assert guard().hold_beyond and not guard(mix='off').hold_beyond
