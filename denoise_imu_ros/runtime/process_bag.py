# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""
Offline bag processing with the online pipeline: ``denoise-imu process-bag``.

The output bag holds every input topic unchanged plus ``/imu/corrected``, ``/imu/data``
(the gravity-aided orientation, with the model file's filter settings) and
``/imu/attitude``, computed by the same :class:`~denoise_imu_ros.pipeline.online.OnlineDenoiser`
the node runs, so the numbers are those the node would publish for that input.
ROS 1 bags are first converted to ROS 2 with ``rosbags.convert``.
"""

from __future__ import annotations

from pathlib import Path
import re
import tempfile
from typing import Any, Callable, Iterator

import numpy as np
from rosbags.convert import convert, ConverterError
from rosbags.rosbag2 import (CompressionFormat, CompressionMode, StoragePlugin, Writer,
                             WriterError)

from .advice import ambiguous_rest
from .outputs import Outputs
from .settings import Settings
from ..core.atomic import atomic_output
from ..core.errors import DatasetError
from ..core.limits import check_rate
from ..core.modelfile import ModelFile, read_model_file
from ..core.msgs import stamp_ns
from ..data.bags import (BAG_TYPES, CORRUPT, IMU_TYPE, is_compressed, messages_as_written,
                         open_bag, pick_connections, TYPESTORE)
from ..pipeline.online import Drop, DROP_CAUSES, FORWARD_JUMP_S

OUTPUT_TOPICS = ('imu/corrected', 'imu/data', 'imu/attitude')  # the node's, relative
MAX_CLOCK_JUMPS = 10  # stamp jumps of over FORWARD_JUMP_S a bag may hold (restarts)
ATTITUDE_TYPE = 'geometry_msgs/msg/QuaternionStamped'
_NAME_TOKEN = re.compile(r'[A-Za-z_][A-Za-z0-9_]*')


def output_topics(namespace: str = '/') -> tuple[str, str, str]:
    """Resolve the node's output topics in ``namespace``, as ROS resolves them."""
    tokens = [t for t in namespace.split('/') if t]
    if not all(_NAME_TOKEN.fullmatch(t) for t in tokens):
        raise DatasetError(f'--namespace {namespace!r}: not a ROS namespace (names of '
                           'letters, digits and _, not starting with a digit, between /)')
    prefix = ''.join(f'/{t}' for t in tokens)
    corrected, fused, attitude = (f'{prefix}/{t}' for t in OUTPUT_TOPICS)
    return corrected, fused, attitude


def _ros2_source(src: Path, workdir: Path) -> Path:
    """Return the bag itself if it is ROS 2 (not one .bag file), else its ROS 2 copy."""
    if not (src.is_file() and src.suffix == '.bag'):
        return src
    dst = workdir / 'converted'
    try:
        convert([src], dst, dst_storage='sqlite3', dst_version=9, compress=None,
                compress_mode='file', default_typestore=None, typestore=TYPESTORE,
                exclude_topics=[], include_topics=[], exclude_msgtypes=[], include_msgtypes=[])
    except (ConverterError, *CORRUPT) as err:
        raise DatasetError(f'{src}: cannot read ROS 1 bag: {" ".join(str(err).split())[:120]}'
                           ) from err
    return dst


def stamp_order(stamps: np.ndarray, jump_ns: int) -> np.ndarray:
    """
    Return the order the pipeline takes IMU messages in: by stamp within each session.

    A stamp more than ``jump_ns`` behind the newest of its session (in the order the bag
    was written, as the node received them) starts a new session (a clock set back, a
    driver restarted): sorting across it would interleave two recordings; the pipeline
    resets there instead, as the node does.
    """
    session = np.zeros(len(stamps), dtype=np.int64)
    k, newest = 0, None
    for i, t in enumerate(stamps.tolist()):
        if newest is not None and t < newest - jump_ns:
            k, newest = k + 1, t
        else:
            newest = t if newest is None else max(newest, t)
        session[i] = k
    return np.lexsort((stamps, session))


def check_one_clock(stamps: np.ndarray, turn: np.ndarray, src: object) -> int:
    """
    Refuse IMU stamps that jump between clocks, back and forth, on one topic.

    A clock set back or a driver restarted is a new session, and a bag may hold a few;
    more than MAX_CLOCK_JUMPS jumps of over a minute (either way, in stamp order within
    sessions) is two clocks mixed on one topic (two drivers, or one mixing clocks): the
    outputs would be as many one-sample recordings. Returns how many sessions begin
    after the first (stamps set back).
    """
    steps = np.diff(stamps[turn])
    back = int((steps < 0).sum())  # each a session
    jumps = int((steps > FORWARD_JUMP_S * 1e9).sum()) + back
    if jumps > MAX_CLOCK_JUMPS:
        raise DatasetError(f'{src}: its IMU stamps jump between clocks {jumps} times (more '
                           f'than {FORWARD_JUMP_S:g} s, back and forth): two clocks on one '
                           'topic? Re-stamp the IMU on one clock, or keep one publisher')
    return back


def _check_free(rd: Any, names: tuple[str, ...], src: Path) -> None:
    """Refuse a bag that has an output topic already: the two would mix on one topic."""
    topics = {c.topic for c in rd.connections}
    taken = sorted(topics & set(names))
    if taken:
        k = 1
        while topics & set(output_topics(f'/denoised{k if k > 1 else ""}')):
            k += 1  # a namespace this bag has none of the outputs in
        free = f'/denoised{k if k > 1 else ""}'
        raise DatasetError(f'{src}: it has {", ".join(taken)} already, which the output would '
                           'mix with the new one: write the outputs in another namespace, '
                           f'e.g. --namespace {free} ({free}/imu/corrected, ...)')


def _writer(path: Path, rd: Any, plugin: StoragePlugin, compress: bool | None) -> Writer:
    """Return the output bag's writer; zstd where asked, else where the input has it."""
    wr = Writer(path, version=9, storage_plugin=plugin)
    if is_compressed(rd) if compress is None else compress:
        wr.set_compression(CompressionMode.STORAGE if plugin == StoragePlugin.MCAP
                           else CompressionMode.MESSAGE, CompressionFormat.ZSTD)
    return wr


class _BagOutputs:
    """The node's outputs (:class:`Outputs`), written at their input's receive time."""

    def __init__(self, wr: Writer, names: tuple[str, ...], loaded: ModelFile,
                 settings: Settings) -> None:
        self._wr, self._received = wr, 0
        wanted = (True, settings.publish_fused, True)  # imu/data only where the node has it
        corrected, fused, attitude = (
            self._sender(name, msgtype) if want else None
            for name, msgtype, want in zip(names, (IMU_TYPE, IMU_TYPE, ATTITUDE_TYPE), wanted))
        self.outputs = Outputs(BAG_TYPES, corrected, fused, attitude, settings.fixed_frame,
                               np.zeros(9), np.zeros(9))
        settings.configure(self.outputs, loaded)

    def _sender(self, name: str, msgtype: str) -> Callable[[Any], None]:
        topic = self._wr.add_connection(name, msgtype, typestore=TYPESTORE)
        return lambda m: self._wr.write(topic, self._received,
                                        TYPESTORE.serialize_cdr(m, msgtype))

    def send(self, msg: Any, out: Any, received: int) -> None:
        """Write what the node publishes of one sample, at ``received`` (ns)."""
        self._received = received
        self.outputs.send(msg, out)


def _in_stamp_order(rd: Any, wr: Writer, copy: dict[int, Any], imu_ids: set[int],
                    stamps: np.ndarray, turn: np.ndarray, src: Path
                    ) -> Iterator[tuple[Any, int]]:
    """
    Copy every message; yield the IMU ones in stamp order, each with its receive time.

    ``stamps`` are the first pass's, ``turn`` their order (the i-th to go): a message is
    held only until its turn comes.
    """
    waiting: dict[int, tuple[Any, int]] = {}  # received, its turn not come
    k, done = -1, 0
    for conn, stamp, raw in messages_as_written(rd):
        wr.write(copy[conn.id], stamp, raw)
        if conn.id not in imu_ids:
            continue
        k += 1
        msg = rd.deserialize(raw, conn.msgtype)
        if k >= len(stamps) or stamp_ns(msg.header) != stamps[k]:
            raise DatasetError(f'{src}: its IMU messages came back in another order the '
                               'second time they were read')
        waiting[k] = msg, stamp
        while done < len(turn) and turn[done] in waiting:
            yield waiting.pop(turn[done])
            done += 1
    if done != len(stamps):
        raise DatasetError(f'{src}: {len(stamps) - done} IMU messages read the first time '
                           'were not there the second')


def process_bag(src: str | Path, dst: str | Path, settings: Settings,
                imu_topic: str | None = None, storage: str = 'mcap',
                compress: bool | None = None, namespace: str = '/',
                warn: Callable[[str], None] = lambda said: None) -> dict[str, int]:
    """
    Copy a bag, add the corrected IMU, orientation and attitude; return the counts.

    The bag is read in the order it was written, what the node received
    (:func:`~denoise_imu_ros.data.bags.messages_as_written`: a host clock stepped back
    steps the receive times too). Its IMU samples go through the pipeline in header-stamp
    order within each run (a recorder's transport latency reorders receive times, and the
    pipeline would drop every late one); a stamp set back starts a new run, as in the
    node (:func:`stamp_order`; said through ``warn``). Each output is written with its
    input's receive time. A first pass reads only the stamps; the second holds a message
    only until its turn comes, so memory follows how far the bag is out of order, not its
    length. Copied
    topics keep their recorded QoS; ``compress`` (zstd) defaults to the input's compression.
    The outputs are the node's topics in ``namespace``; a bag that has one already is
    refused (the two would mix on one topic). ``settings`` are the node's parameters
    (:class:`~denoise_imu_ros.runtime.settings.Settings`, the model among them); what is
    written and withheld is the node's under them, built by the same code
    (:mod:`denoise_imu_ros.runtime.outputs`). ``warn``
    is also told what the node's ``/diagnostics`` would say at the end (a turn-on bias
    that may have been a slow turn).
    """
    src = Path(src)
    if not src.exists():
        raise DatasetError(f'{src}: bag not found')
    names = output_topics(namespace)
    loaded = read_model_file(settings.model)
    den = settings.denoiser(loaded)
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    with tempfile.TemporaryDirectory() as tmp, atomic_output(dst) as partial:
        try:
            with open_bag(_ros2_source(src, Path(tmp))) as rd:
                _check_free(rd, names, src)
                imu_ids = {c.id for c in pick_connections(rd, imu_topic, (IMU_TYPE,), 'IMU',
                                                          src)}
                # all topics, as the second pass reads them: the same order, ties included
                stamps = np.array([stamp_ns(rd.deserialize(raw, c.msgtype).header)
                                   for c, _, raw in messages_as_written(rd)
                                   if c.id in imu_ids], dtype=np.int64)
                turn = stamp_order(stamps, round(den.time_jump_s * 1e9))  # the i-th to go
                back = check_one_clock(stamps, turn, src)
                if back:
                    warn(f'{src}: its IMU stamps step back {back} time{"s" * (back > 1)} as '
                         'written (a clock set back, a driver restarted): each starts a new '
                         'run, as the node that received them did')
                check_rate(stamps[turn], den.rate_hz, src)
                with _writer(partial, rd, plugin, compress) as wr:
                    copy = {c.id: wr.add_connection(
                        c.topic, c.msgtype, typestore=rd.typestore,
                        offered_qos_profiles=getattr(c.ext, 'offered_qos_profiles', ()))
                        for c in rd.connections}
                    outputs = _BagOutputs(wr, names, loaded, settings)
                    for msg, received in _in_stamp_order(rd, wr, copy, imu_ids, stamps, turn,
                                                         src):
                        res = den.process_imu(msg)
                        if not isinstance(res, Drop):
                            outputs.send(msg, res, received)
        except (*CORRUPT, WriterError, FileExistsError) as err:
            raise DatasetError(f'{src} -> {dst}: {err}') from err
    if den.rest is not None and den.rest.ambiguous:
        warn(ambiguous_rest(den.rest))
    return {**{k: v for k, v in den.counts.items() if v or k in DROP_CAUSES},
            **{k: v for k, v in outputs.outputs.counts.items() if v}}
