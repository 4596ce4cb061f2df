# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
``gyro_denoiser``: ``imu/data_raw`` into ``imu/corrected``, ``imu/data`` and ``imu/attitude``.

``imu/data`` is the imu_tools contract (what imu_filter_madgwick publishes): the
gravity-aided orientation of the corrected gyro, with its covariance, the corrected
angular velocity and the accelerometer as ``imu/corrected`` carries it (less the bias the
model fitted, where its cross-validation found that bias carries to unseen recordings).
``imu/attitude`` is the paper's open-loop integral of the corrected gyro.

A thin ROS wrapper around :class:`~denoise_imu_ros.pipeline.online.OnlineDenoiser`: it converts
messages, owns the parameters and topics, and reports on ``/diagnostics``. Header stamps
and frame ids are copied from the input, never re-stamped.
"""

from __future__ import annotations

from collections import deque
from pathlib import Path
import re
import sys
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import QuaternionStamped
import numpy as np
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
import rclpy
from rclpy.clock import Clock, ClockType
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.qos_overriding_options import QoSOverridingOptions
from rclpy.utilities import remove_ros_args
from sensor_msgs.msg import Imu
from std_srvs.srv import Trigger
import yaml

from . import diagnostics
from .advice import blend_warnings, deployment_warning, rest_warnings
from .outputs import Outputs
from .rclpy_internals import (given_parameters, integer_given_for_double, RCLError,
                              RCLInvalidROSArgsError, take_waiting)
from .settings import section_applies, Settings
from ..core import msgs
from ..core.errors import DenoiseError
from ..core.modelfile import read_model_file
from ..pipeline.online import Drop, Event


def _param(description: str, read_only: bool = False, floats: tuple | None = None,
           ints: tuple | None = None, dynamic: bool = False) -> ParameterDescriptor:
    d = ParameterDescriptor(description=description, read_only=read_only,
                            dynamic_typing=dynamic)
    if floats:
        d.floating_point_range = [FloatingPointRange(from_value=floats[0], to_value=floats[1])]
    if ints:
        d.integer_range = [IntegerRange(from_value=ints[0], to_value=ints[1], step=1)]
    return d


# Every parameter, as Settings declares it: (name, default, descriptor).
# config/gyro_denoiser.yaml mirrors it.
DRAIN_MAX = 50  # queued messages one callback takes after its own
NAMESAKE_CHECK_S = 2.0  # s after start-up, discovery done, to look for a node of this name

PARAMETERS = [(name, default, _param(spec.description, spec.read_only, spec.floats, spec.ints,
                                     spec.switches is not None))
              for name, default, spec in Settings.specs()]


class GyroDenoiser(Node):
    """Learned gyro correction of every IMU sample, plus the integrated attitude."""

    def __init__(self, **kwargs) -> None:
        super().__init__('gyro_denoiser', **kwargs)
        try:
            self.declare_parameters('', PARAMETERS)
        except ParameterException as err:  # a wrong type or range given at start-up
            why = ' '.join(str(err).split())
            given = integer_given_for_double(err)
            if given:  # ROS does not convert: say how to write it
                why += f' (write a decimal with a point: {given[0]}:={given[1]}.0)'
            raise DenoiseError(f'bad parameter: {why}') from err
        settings = self._settings()
        loaded = read_model_file(settings.model)  # DenoiseError: handled in main()
        fusion = settings.fusion(loaded) if settings.publish_fused else None
        rest_choice = settings.choice('rest_bias')
        self._denoiser = settings.denoiser(loaded)
        self._model_rate = self._denoiser.rate_hz
        self._loaded = loaded
        self._not_recommended = deployment_warning(loaded)  # kept as a diagnostics WARN
        self._types = msgs.rclpy_types()
        self._fixed_frame = settings.fixed_frame

        for name, value in self._given_parameters().items():  # rcl's own error is C spam
            if name.startswith('qos_overrides.') and name.endswith('.depth') and (
                    isinstance(value.value, int) and value.value < 1):
                raise DenoiseError(f'bad parameter: {name} must be a positive integer, not '
                                   f'{value.value}')
        try:  # the QoS overrides given as parameters are read here
            self._create_topics(fusion is not None)
        except (RuntimeError, ParameterException, RCLError) as err:
            why = ' '.join(str(err).split())
            raise DenoiseError(f'bad parameter: a qos_overrides value rclpy cannot use ({why}; '
                               'depth: a positive integer, reliability: reliable or '
                               'best_effort, history: keep_last or keep_all)') from err
        self.create_service(Trigger, '~/reset_attitude', self._on_reset)
        # wall-clock timers: with use_sim_time and no /clock (a bag played without --clock)
        # sim time stands still, and the rate check and diagnostics must still run
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.create_timer(1.0, self._publish_diagnostics, clock=steady)
        self._waiting_timer = self.create_timer(10.0, self._still_waiting, clock=steady)
        self.namesakes = 0  # other nodes of this name, once discovery has seen them
        self._namesake_timer = self.create_timer(NAMESAKE_CHECK_S, self._check_namesakes,
                                                 clock=steady)

        self._last_input: float | None = None  # time.monotonic() of the last message
        self._infer_s: deque[float] = deque(maxlen=1000)
        self._frame = ''  # the IMU's frame_id, from its last message
        self._outputs = Outputs(  # covariances and embedding: _apply_parameters
            self._types, self._pub_imu.publish,
            None if self._pub_fused is None else self._pub_fused.publish,
            self._pub_att.publish, self._fixed_frame, np.zeros(9), np.zeros(9))
        self._apply_parameters()
        self.add_post_set_parameters_callback(self._on_parameters)
        field = loaded.config.receptive_field
        rest = self._denoiser.rest
        self.get_logger().info(
            f'model {loaded.path} ({self._model_rate:.1f} Hz, receptive field {field} '
            f'sample{"s" if field > 1 else ""}, '
            f'{"compiled" if self._denoiser.engine.compiled else "numpy"} step); turn-on '
            + ('bias not removed' if rest is None else
               'bias removed: estimated from stillness, until then '
               f'{[round(b, 5) for b in rest.settings.prior_rad_s]} rad/s')
            + ('' if self._denoiser.track is None else
               f'; output bias tracked (VQF: {self._denoiser.track.settings.describe()})')
            + ('' if self._denoiser.guard is None else
               '; no correction beyond the motion trained on (gyro '
               f'{self._denoiser.guard.envelope.gyro_rad_s:.2f} rad/s, accelerometer '
               f'{self._denoiser.guard.envelope.accel_offset_m_s2:.1f} m/s^2 from gravity)')
            + ('' if self._denoiser.vertical is None else
               "; no correction about the vertical (taught without its poses' heading)")
            + f'; {self._sub.topic_name} -> {self._pub_imu.topic_name} (accelerometer '
            + ('as it came' if not self._denoiser.corrected_accel_bias.any() else
               f'less {self._denoiser.corrected_accel_bias.round(4).tolist()} m/s^2') + ')'
            + ('' if fusion is None else
               f', {self._pub_fused.topic_name} (VQF: tau_acc {fusion.tau_acc_s:g} s, bias '
               f'estimation {"on" if fusion.bias_estimation else "off"}, accelerometer bias '
               + ('removed: none stored' if not any(fusion.accel_bias_m_s2) else
                  f'removed {[round(b, 4) for b in fusion.accel_bias_m_s2]} m/s^2')
               + ("; roll and pitch of VQF's defaults on the raw IMU" if fusion.classical_tilt
                  else '') + ')')
            + f', {self._pub_att.topic_name}')
        if self._not_recommended:
            self.get_logger().warning(self._not_recommended)
        for said in [*rest_warnings(loaded, rest_choice),
                     *blend_warnings(loaded, settings.choice('classical_blend'))]:
            self.get_logger().warning(said)
        # rclpy ignores a value given for a parameter no node declares: say so, since a
        # misspelt name would otherwise run with the default (the QoS overrides are
        # declared by now, with the publishers and the subscription)
        given = self._given_parameters()
        self.unknown_parameters = sorted(n for n in given if not self.has_parameter(n))
        if self.unknown_parameters:
            self.get_logger().warning(
                f'ignored parameters this node does not have: '
                f'{", ".join(self.unknown_parameters)} (gyro_denoiser --help lists its own)')

    def _given_parameters(self) -> dict:
        """Return the parameter values given at start-up, declared or not."""
        return given_parameters(self)

    def _create_topics(self, fused: bool) -> None:
        """Create the publishers and the subscription, with their QoS overrides."""
        reliable = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
        overridable = QoSOverridingOptions.with_default_policies
        self._pub_imu = self.create_publisher(Imu, 'imu/corrected', reliable,
                                              qos_overriding_options=overridable())
        self._pub_fused = self.create_publisher(
            Imu, 'imu/data', reliable, qos_overriding_options=overridable()) if fused else None
        self._pub_att = self.create_publisher(QuaternionStamped, 'imu/attitude', reliable,
                                              qos_overriding_options=overridable())
        self._pub_diag = self.create_publisher(DiagnosticArray, '/diagnostics', 10)
        self._sub = self.create_subscription(
            Imu, 'imu/data_raw', self._on_imu,
            QoSProfile(history=HistoryPolicy.KEEP_LAST,
                       depth=self.get_parameter('input_queue_depth').value,
                       reliability=ReliabilityPolicy.BEST_EFFORT),
            qos_overriding_options=overridable())

    # -- parameters ---------------------------------------------------------------
    def _settings(self) -> Settings:
        """Return the parameters' values as one checked object (DenoiseError if refused)."""
        return Settings.from_values({name: self.get_parameter(name).value
                                     for name, _, _ in PARAMETERS})[0]

    def _apply_parameters(self) -> None:
        """Apply the parameters that may change while the node runs."""
        settings = self._settings()
        settings.configure(self._outputs, self._loaded)
        settings.retune(self._denoiser)

    def _on_parameters(self, _params: list) -> None:
        self._apply_parameters()

    # -- data ---------------------------------------------------------------------
    def _on_imu(self, msg: Imu) -> None:
        """
        Handle a message, then those already waiting behind it, in this one callback.

        rclpy's executor costs more per callback than the node's own work: one wake per
        message cannot keep up at 1 kHz. Taking the queued messages here pays it once per
        burst; DRAIN_MAX bounds the burst so that timers and services still run.
        """
        self._handle(msg)
        for _ in range(DRAIN_MAX):
            taken = take_waiting(self._sub, Imu)
            if taken is None:
                return
            self._handle(taken)

    def _handle(self, msg: Imu) -> None:
        if self._waiting_timer is not None:
            self._waiting_timer.cancel()
            self._waiting_timer = None
        self._last_input = time.monotonic()
        t0 = time.perf_counter()
        out = self._denoiser.process_imu(msg)
        if isinstance(out, Drop):
            self.get_logger().warning(f'dropped an IMU message: {out.value.replace("_", " ")}',
                                      throttle_duration_sec=5.0)
            return
        if out.event in (Event.GAP, Event.TIME_JUMP):
            self.get_logger().warning(
                f'{"stamp gap" if out.event == Event.GAP else "time jump"} before '
                f'{out.stamp_ns} ns: network history restarted'
                + (', attitude re-initialised' if out.event == Event.TIME_JUMP else
                   ', attitude held (not published for this sample)'),
                throttle_duration_sec=5.0)

        self._frame = msg.header.frame_id
        self._outputs.send(msg, out)  # what it withholds: outputs.py
        self._infer_s.append(time.perf_counter() - t0)

    @property
    def corrected_withheld(self) -> int:
        """Count the accepted samples whose imu/corrected was not published."""
        return self._outputs.counts['corrected_withheld']

    @property
    def fused_withheld(self) -> int:
        """Count the accepted samples whose imu/data was not published."""
        return self._outputs.counts['fused_withheld']

    @property
    def attitude_withheld(self) -> int:
        """Count the accepted samples whose imu/attitude was not published."""
        return self._outputs.counts['attitude_withheld']

    def _on_reset(self, _request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        self._denoiser.reset_attitude()
        response.success = True
        response.message = ('attitude (and imu/data orientation) re-initialised from the '
                            'accelerometer at the next sample')
        return response

    # -- monitoring ---------------------------------------------------------------
    def input_rate_hz(self) -> float:
        """Return the input rate, the pipeline's: its recent median interval's (0 if unknown)."""
        return self._denoiser.input_rate_hz

    def _imu_frame(self) -> str:
        """Return the IMU's frame_id, from its last message (diagnostics name the device)."""
        return self._frame

    def _publish_diagnostics(self) -> None:
        silent_s = None if self._last_input is None else time.monotonic() - self._last_input
        said = diagnostics.status(self._denoiser, self._outputs.counts, silent_s,
                                  self.resolve_topic_name('imu/data_raw'),
                                  self._not_recommended, self._infer_s)
        if said.level == diagnostics.Level.ERROR:
            self.get_logger().error(said.message, throttle_duration_sec=10.0)
        status = DiagnosticStatus(name=f'{self.get_fully_qualified_name()}: gyro correction',
                                  hardware_id=self._imu_frame(), level=bytes([said.level]),
                                  message=said.message,
                                  values=[KeyValue(key=k, value=v)
                                          for k, v in said.values.items()])
        array = DiagnosticArray(status=[status])
        array.header.stamp = self.get_clock().now().to_msg()
        self._pub_diag.publish(array)

    def _check_namesakes(self) -> None:
        """Warn once when another node has this one's name: they share every topic."""
        self._namesake_timer.cancel()
        mine = (self.get_name(), self.get_namespace())
        self.namesakes = sum(n == mine for n in self.get_node_names_and_namespaces()) - 1
        if self.namesakes > 0:
            self.get_logger().warning(
                f'{self.namesakes} other node(s) named {self.get_fully_qualified_name()}: '
                'they share its parameters, /diagnostics status, reset service and outputs '
                '(imu/corrected, ...); give each its own name and namespace '
                '(-r __node:=NAME -r __ns:=/NS)')

    def _still_waiting(self) -> None:
        sub = self.resolve_topic_name('imu/data_raw')
        self.get_logger().warning(f'still waiting for data on {sub}')


USAGE = """usage: gyro_denoiser [--ros-args -p NAME:=VALUE ... --params-file FILE ...]

Corrects imu/data_raw into imu/corrected, imu/data and imu/attitude with a learned gyro model.
Parameters (see config/gyro_denoiser.yaml): """ + ', '.join(
    name for name, _, _ in PARAMETERS) + """.
Later --params-file and -p arguments override earlier ones: put -p after --params-file.
Example: gyro_denoiser --ros-args --params-file config/gyro_denoiser.yaml -p model:=tumvi
"""


def foreign_params_files(args: list[str], node_name: str) -> dict[str, list[str]]:
    """
    Return the ``--params-file`` files none of whose sections applies to ``node_name``.

    rcl applies a section keyed ``/**``, the node's name or a pattern matching it
    (``*`` one name, ``**`` any number) and drops the others without a word: a file keyed
    to another node (another name, a namespace it does not run in) does nothing.
    File -> its sections' keys.
    """
    files = [args[k + 1] for k, a in enumerate(args[:-1]) if a == '--params-file']
    foreign = {}
    for path in files:
        try:
            keys = list(yaml.safe_load(Path(path).read_text(encoding='utf-8')) or {})
        except (OSError, UnicodeDecodeError, yaml.YAMLError, TypeError):
            continue  # rcl has said what is wrong with it already
        if not any(section_applies(str(key), node_name) for key in keys):
            foreign[path] = [str(key) for key in keys]
    return foreign


def main(args: list[str] | None = None) -> int:
    """Entry point of ``gyro_denoiser`` (console script and ``ros2 run``)."""
    try:
        return _run(args)
    except KeyboardInterrupt:  # a Ctrl-C (rclpy's handler, then Python's) raised while
        return 0               # the first half of it, a shut-down context, was handled


def _run(args: list[str] | None) -> int:
    """Parse the arguments, build the node and spin it until shut down; the exit code."""
    # args, as in tests, holds no program name; sys.argv does
    try:
        rest = remove_ros_args(sys.argv)[1:] if args is None else remove_ros_args(args)
    except RCLInvalidROSArgsError as err:  # e.g. a missing or malformed params file
        where = re.sub(r',? at \S+:\d+', '', str(err))  # rcl's source locations
        print(f'gyro_denoiser: error: {" ".join(where.split())}', file=sys.stderr)
        return 1
    if rest and rest[0] in ('-h', '--help'):
        print(USAGE, end='')
        return 0
    if rest:
        print(f'gyro_denoiser: error: unknown arguments {" ".join(rest)!r}; parameters go '
              'after --ros-args, e.g. gyro_denoiser --ros-args -p model:=tumvi',
              file=sys.stderr)
        return 1
    rclpy.init(args=args)
    node = None
    try:
        node = GyroDenoiser()
        name = node.get_fully_qualified_name()
        for path, keys in foreign_params_files(sys.argv if args is None else args,
                                               name).items():
            node.get_logger().warning(
                f'{path}: its parameters are for {", ".join(keys)}, none for this node '
                f'({name}): nothing of it applies (key it /**: or {name}:)')
        # its own executor: rclpy.spin's global one is None when a signal has already
        # shut rclpy down (Ctrl-C during start-up); this one then returns at once
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        executor.spin()
    except DenoiseError as err:
        print(f'gyro_denoiser: error: {err}', file=sys.stderr)
        return 1
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except RCLError:  # a signal shut rclpy down as the executor built its wait set
        if rclpy.ok():
            raise
    finally:
        if node is not None:
            node.destroy_node()
        shutdown_rclpy()
    return 0


def shutdown_rclpy() -> None:
    """Shut rclpy down unless a signal did: ``try_shutdown`` can race the signal's own."""
    try:
        rclpy.try_shutdown()
    except RCLError:  # the signal's shutdown landed between its check and its call
        if rclpy.ok():
            raise


if __name__ == '__main__':
    sys.exit(main())
