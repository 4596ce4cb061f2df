# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
The node's settings in one object: its parameters, read from ROS or from a params YAML.

:class:`Settings` holds every parameter of ``gyro_denoiser`` with its default, range and
help text (the node declares exactly these), checks a value as ROS does, and builds what
they configure: the pipeline (:meth:`Settings.denoiser`) and the covariances the
outputs carry (:meth:`Settings.covariances`). The node reads it from its parameters,
``process-bag --params-file`` from the same YAML the node takes (keyed ``/**:``), so that
``process-bag`` writes what the node publishes under any configuration.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
import math
from pathlib import Path
import re
from typing import Any, Mapping, NamedTuple

import numpy as np
import yaml

from .outputs import Outputs
from ..core.errors import OptionError
from ..core.limits import MAX_GAP_FACTOR, RATE_TOLERANCE
from ..core.modelfile import gyro_covariance, MODEL_HELP, ModelFile
from ..core.schema import AS_IT_CAME
from ..pipeline.fusion import FusionSettings, orientation_covariance
from ..pipeline.online import OnlineDenoiser

__all__ = ['NODE_NAME', 'section_applies', 'Spec', 'Settings', 'SWITCH_WORDS']

NODE_NAME = '/gyro_denoiser'  # its fully qualified name in the root namespace
SWITCH_WORDS = {'on': True, 'true': True, 'off': False, 'false': False}
RANGE_TOLERANCE = 1e-6  # rclpy accepts a value this close (relative) to a range's end
# parameters every rclpy node has: a file may set them without being about this node
EVERY_NODE = ('use_sim_time', 'start_type_description_service')


class _RosYaml(yaml.SafeLoader):
    """PyYAML's safe loader reading numbers as rcl's parser does: 1e-2 is a float too."""


_RosYaml.add_implicit_resolver(
    'tag:yaml.org,2002:float',
    re.compile(r'^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$'),
    list('-+0123456789.'))


class Spec(NamedTuple):
    """What ROS is told of one parameter: its help, whether fixed at start, its range."""

    description: str
    read_only: bool = False
    floats: tuple[float, float] | None = None
    ints: tuple[int, int] | None = None
    switches: tuple[bool, ...] | None = None  # 'model' or one of these (on/off words)


def _p(default: Any, description: str, **spec: Any) -> Any:
    return field(default=default, metadata={'spec': Spec(description, **spec)})


@dataclass(frozen=True)
class Settings:
    """Every parameter of the node, each with its default, help and range (``Spec``)."""

    model: str = _p('euroc', f'The model: {MODEL_HELP}.', read_only=True)
    fixed_frame: str = _p(
        'odom', 'frame_id of imu/attitude: gravity-aligned at start (roll/pitch from the '
        'accelerometer), yaw 0 at start.', read_only=True)
    embed_attitude: bool = _p(
        False, 'Also write the attitude into imu/corrected orientation (otherwise '
        'orientation_covariance[0] = -1: no orientation).')
    orientation_stddev: float = _p(
        0.05, 'rad; orientation covariance diagonal when embed_attitude is on.',
        floats=(0.0, math.pi))
    angular_velocity_stddev: float = _p(
        -1.0, "rad/s; < 0: the model's, each message's own variance where its file has "
        'one (fit-variance --attach), else the per-axis residual std it measured on its '
        'validation data (zeros, "unknown" to ROS, for a file without it); 0: zeros.',
        floats=(-1.0, 10.0))
    linear_acceleration_stddev: float = _p(
        -1.0, "m/s^2; < 0: the model's, each message's own variance where its file has one "
        '(fit-variance --attach) fitted on the accelerometer published (less the same bias: '
        "fusion_accel_bias), else the input message's covariance; >= 0: that on the diagonal "
        'of every message (0: zeros, "unknown" to ROS).', floats=(-1.0, 100.0))
    max_gap_factor: float = _p(
        MAX_GAP_FACTOR, 'A stamp gap above this many nominal periods restarts the network '
        'history (warm-up) and holds the attitude across the gap.', floats=(1.5, 1000.0))
    time_jump_threshold: float = _p(
        1.0, 's; a stamp this far behind the last one restarts the run (a bag loop, a clock '
        'stepped back), the turn-on bias found kept; '
        'smaller backward steps are dropped as out of order.', floats=(0.0, 3600.0))
    rate_tolerance: float = _p(
        RATE_TOLERANCE, "Relative input-rate mismatch to the model rate (the stream's median "
        'interval, or a run of intervals) that withholds the outputs and is a diagnostics '
        'error.', floats=(0.0, 1.0))
    input_queue_depth: int = _p(
        200, 'Subscription depth (sensor-data reliability); bursts beyond it are lost.',
        read_only=True, ints=(10, 10000))
    publish_fused: bool = _p(
        True, 'Publish imu/data: the gravity-aided orientation (VQF) of the corrected gyro '
        'and the accelerometer.', read_only=True)
    fusion_tau_acc: float = _p(
        -1.0, "s; the filter's accelerometer time constant (longer trusts the gyro more); "
        '< 0: the value the model file stores, chosen on its training recordings; 0 is '
        'refused.', read_only=True, floats=(-1.0, 1000.0))
    fusion_bias_estimation: str | bool = _p(
        'model', "The filter's own gyro-bias estimation: 'model' (the model file's choice), "
        "on or off. On stacks a second estimator on the network's correction.",
        read_only=True, switches=(True, False))
    fusion_classical_tilt: str | bool = _p(
        'model', "The orientation's roll and pitch from VQF's defaults on the raw gyro and "
        'accelerometer as received (what runs with no model), its heading from the corrected '
        "gyro: 'model' (where the model file's cross-validation on another power-on found "
        'that tilt lower), on or off.', read_only=True, switches=(True, False))
    fusion_accel_bias: str | bool = _p(
        'model', "The accelerometer bias removed before the filter and from imu/attitude's "
        "initial tilt, and from imu/corrected's and imu/data's accelerometer where the model "
        "file's cross-validation found it carries to unseen recordings: 'model' (the one the "
        'model file fitted on its training poses, if it chose to) or off (none: the '
        'accelerometer as it came).', read_only=True, switches=(False,))
    rest_bias: str | bool = _p(
        'model', "The gyro's turn-on bias, estimated from stillness (at start and later) and "
        "removed before the model, and the output's bias tracked after it where the model "
        "file chose so: 'model' (as the model was trained and cross-validated), on or off "
        '(neither).', read_only=True, switches=(True, False))
    envelope_guard: str | bool = _p(
        'model', 'Beyond the motion the model was trained on (its input envelope), its '
        "input gyro plus a constant instead of its correction, and the output's bias "
        "estimate held through faster rotation: 'model' (where the model file has an "
        'envelope) or off (the correction everywhere, tracked throughout).', read_only=True,
        switches=(False,))
    classical_blend: str | bool = _p(
        'model', "The output blended with the classical pipeline's (the gyro less its "
        'turn-on bias, its bias tracked, no model), and that alone where the acceleration '
        "stays off gravity longer than in training: 'model' (the weight the model file's "
        "cross-validation chose, where it did) or off (the network's output).",
        read_only=True, switches=(False,))
    fused_orientation_stddev: float = _p(
        -1.0, 'rad; imu/data orientation covariance diagonal; < 0: the fused errors the '
        'model file stores (0.05 rad without them); 0: zeros, which ROS reads as "unknown".',
        floats=(-1.0, math.pi))

    def __post_init__(self) -> None:
        """Refuse a value ROS would refuse, or that the node cannot use, in one line."""
        for f in fields(self):
            spec: Spec = f.metadata['spec']
            value = getattr(self, f.name)
            if spec.switches is not None:
                self.choice(f.name)  # refuses a word that is not one
            elif type(value) is not type(f.default):
                given = type(value).__name__
                hint = (f' (write a decimal with a point: {f.name}:={value}.0)'
                        if isinstance(value, int) and isinstance(f.default, float)
                        and not isinstance(value, bool) else '')
                raise OptionError(f'bad parameter: {f.name} must be a '
                                  f'{type(f.default).__name__}, not a {given}{hint}')
            bounds = spec.floats or spec.ints
            if bounds is not None and not _within(value, *bounds):
                raise OptionError(f'bad parameter: {f.name} = {value} is outside '
                                  f'[{bounds[0]}, {bounds[1]}]')
        if not self.fixed_frame.strip():
            raise OptionError('bad parameter: fixed_frame must name a frame (imu/attitude is '
                              'stamped in it), not be empty')
        if self.fusion_tau_acc == 0:
            raise OptionError('bad parameter: fusion_tau_acc must be a time constant above '
                              "0 s, or below 0 for the model file's")

    @classmethod
    def specs(cls) -> list[tuple[str, Any, Spec]]:
        """Return (name, default, spec) of every parameter, in the order the node declares."""
        return [(f.name, f.default, f.metadata['spec']) for f in fields(cls)]

    @classmethod
    def from_values(cls, values: Mapping[str, Any]) -> tuple[Settings, list[str]]:
        """Return the settings of the parameters given and the names that are not any."""
        names = {f.name for f in fields(cls)}
        return (cls(**{k: v for k, v in values.items() if k in names}),
                sorted(k for k in values if k not in names))

    @classmethod
    def from_params_file(cls, path: str | Path, node: str = NODE_NAME
                         ) -> tuple[Settings, list[str]]:
        """
        Return the settings a params YAML gives the node, and the names it does not have.

        As ROS reads the file: every entry whose key selects the node
        (:func:`section_applies`: ``/**``, ``/node``...) in file order, later ones
        overriding, its ``ros__parameters`` with nested keys joined by dots.
        ``qos_overrides.*`` set DDS policies only and :data:`EVERY_NODE` are every
        node's, so neither is counted as unknown. ``node``: the node's fully qualified
        name (``/ns/gyro_denoiser`` in a namespace).
        """
        try:
            with open(path) as f:
                doc = yaml.load(f, Loader=_RosYaml)  # noqa: S506 (a safe loader)
        except OSError as err:
            raise OptionError(f'--params-file {path}: {err.strerror}') from err
        except yaml.YAMLError as err:
            raise OptionError(f'--params-file {path}: not YAML ({" ".join(str(err).split())})'
                              ) from err
        if not isinstance(doc, dict):
            raise OptionError(f'--params-file {path}: not a ROS params file (a mapping of '
                              'node names to ros__parameters)')
        values: dict[str, Any] = {}
        for key, entry in doc.items():
            if section_applies(str(key), node):
                params = entry.get('ros__parameters') if isinstance(entry, dict) else None
                if not isinstance(params, dict):
                    raise OptionError(f'--params-file {path}: {key}: no ros__parameters mapping')
                values.update(_flat(params))
        if not values:
            raise OptionError(f'--params-file {path}: no parameters for {node} (keys: '
                              f'{", ".join(map(str, doc))}; the node reads /** or {node})')
        values = {k: v for k, v in values.items()
                  if not k.startswith('qos_overrides.') and k not in EVERY_NODE}
        return cls.from_values(values)

    def with_(self, **changes: Any) -> Settings:
        """Return a copy with some parameters changed (checked again)."""
        return replace(self, **changes)

    def choice(self, name: str) -> str:
        """Return a model-or-switch parameter as 'model', 'on' or 'off'."""
        value = getattr(self, name)
        switches = next(f.metadata['spec'].switches for f in fields(self) if f.name == name)
        if value == 'model':
            return 'model'
        switch = SWITCH_WORDS.get(value.lower()) if isinstance(value, str) else value
        if isinstance(switch, bool) and switch in switches:
            return 'on' if switch else 'off'
        options = ["'model'"] + ['on' if s else 'off' for s in switches]
        allowed = ', '.join(options[:-1]) + ' or ' + options[-1]
        given = ('on' if value else 'off') if isinstance(value, bool) else repr(value)
        raise OptionError(f'bad parameter: {name} must be {allowed}, not {given}')

    def fusion(self, loaded: ModelFile) -> FusionSettings:
        """Return the model file's filter settings with these overrides applied."""
        chosen = loaded.meta.fusion.chosen
        bias, accel = self.choice('fusion_bias_estimation'), self.choice('fusion_accel_bias')
        tilt = self.choice('fusion_classical_tilt')
        return FusionSettings(
            tau_acc_s=self.fusion_tau_acc if self.fusion_tau_acc > 0 else chosen.tau_acc_s,
            bias_estimation=chosen.bias_estimation if bias == 'model' else bias == 'on',
            accel_bias_m_s2=chosen.accel_bias_m_s2 if accel == 'model' else (0.0, 0.0, 0.0),
            classical_tilt=chosen.classical_tilt if tilt == 'model' else tilt == 'on')

    def denoiser(self, loaded: ModelFile) -> OnlineDenoiser:
        """Return the pipeline these settings run for a model file."""
        fusion = self.fusion(loaded)
        den = OnlineDenoiser.from_model_file(
            loaded, fusion if self.publish_fused else None, self.choice('rest_bias'),
            self.choice('envelope_guard'), self.choice('classical_blend'),
            accel_bias=fusion.accel_bias_m_s2,
            corrected_accel_bias=self.corrected_accel_bias(loaded))
        self.retune(den)
        return den

    def corrected_accel_bias(self, loaded: ModelFile) -> tuple[float, float, float]:
        """
        Return the accelerometer bias imu/corrected (and imu/data) leave out of their reading.

        The filter's (:meth:`fusion`), unless the model file's cross-validation found that
        it does not carry to unseen recordings (a bias that changes at each power-on).
        """
        verdict = loaded.meta.crossval
        if verdict is not None and verdict.accel_deploy == AS_IT_CAME:
            return (0.0, 0.0, 0.0)
        return self.fusion(loaded).accel_bias_m_s2

    def retune(self, den: OnlineDenoiser) -> None:
        """Apply the thresholds that may change while the node runs."""
        den.max_gap_factor = self.max_gap_factor
        den.time_jump_s = self.time_jump_threshold
        den.rate_tolerance = self.rate_tolerance

    def per_sample_gyro(self, loaded: ModelFile) -> bool:
        """Whether imu/corrected carries each sample's gyro variance (the model's, no override)."""
        return loaded.meta.gyro_variance is not None and self.angular_velocity_stddev < 0

    def per_sample_accel(self, loaded: ModelFile) -> bool:
        """
        Whether imu/corrected carries each sample's accelerometer variance.

        The model's, where the accelerometer published is the one it was fitted on (less
        the same bias: not after ``fusion_accel_bias`` or a later cross-validation changed
        it), and no override.
        """
        spec = loaded.meta.accel_variance
        return (spec is not None and self.linear_acceleration_stddev < 0
                and spec.accel_bias_m_s2 == tuple(self.corrected_accel_bias(loaded)))

    def accel_covariance(self) -> np.ndarray | None:
        """Return imu/corrected's fixed accelerometer covariance; None: the input's own."""
        std = self.linear_acceleration_stddev
        return None if std < 0 else np.diag([std ** 2] * 3).ravel()

    def configure(self, out: Outputs, loaded: ModelFile) -> None:
        """Set what the outputs embed and the covariances they carry (arrays built once)."""
        out.embed_attitude = self.embed_attitude
        out.gyro_cov = np.array(gyro_covariance(loaded, self.angular_velocity_stddev))
        out.orientation_cov = np.diag([self.orientation_stddev ** 2] * 3).ravel()
        out.fused_cov = np.array(orientation_covariance(loaded.meta,
                                                        self.fused_orientation_stddev))
        out.per_sample_gyro = self.per_sample_gyro(loaded)
        out.accel_cov = self.accel_covariance()
        out.per_sample_accel = self.per_sample_accel(loaded)


def _within(value: float, low: float, high: float) -> bool:
    """Whether ``value`` is in [low, high] as ROS checks a range: within 1e-6 at the ends."""
    return all(side or math.isclose(value, end, rel_tol=RANGE_TOLERANCE)
               for side, end in ((value >= low, low), (value <= high, high)))


def section_applies(key: str, node_name: str) -> bool:
    """Whether a params file's section key selects the node ``node_name`` (/ns/name)."""
    pattern = re.escape('/' + key.lstrip('/')).replace(r'/\*\*', r'(/[^/]+)*')
    return re.fullmatch(pattern.replace(r'\*', '[^/]+'), node_name) is not None


def _flat(params: Mapping[str, Any], prefix: str = '') -> dict[str, Any]:
    """Return nested parameters with their keys joined by dots, as ROS names them."""
    out: dict[str, Any] = {}
    for key, value in params.items():
        if isinstance(value, dict):
            out.update(_flat(value, f'{prefix}{key}.'))
        else:
            out[f'{prefix}{key}'] = value
    return out
