"""Columnar CDR decoding: the bound fields of many messages of one channel at once, by numpy.

The per-message selective decoder (:mod:`fretc.logs.ros.selective`) walks each message in
Python; on a one-hour log that walk is most of an audit's cost. A :class:`ColumnarDecoder`
walks the same layout for a whole group of messages at once (the messages of one channel in
one MCAP chunk): every message's offset is an element of an int64 array, each field moves
all of them with one numpy operation, and each bound field is gathered from the chunk's
bytes into one column.

Design notes: ARCHITECTURE.md, `logs/ros/columnar.py`."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any, TYPE_CHECKING

import numpy as np

from fretc.logs.ros.selective import HEADER_STAMP, Path, _NotCovered, _tree

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

__all__ = ["ColumnarDecoder", "columnar_decoder", "Segment", "RANGES"]

_SIZE = {"bool": 1, "byte": 1, "char": 1, "int8": 1, "uint8": 1, "int16": 2, "uint16": 2,
         "int32": 4, "uint32": 4, "int64": 8, "uint64": 8, "float32": 4, "float64": 8}
_DTYPE = {"bool": "u1", "byte": "u1", "char": "u1", "int8": "i1", "uint8": "u1",
          "int16": "<i2", "uint16": "<u2", "int32": "<i4", "uint32": "<u4",
          "float32": "<f4", "float64": "<f8"}
_LASER = "sensor_msgs/msg/LaserScan"
#: The column key of a LaserScan's ranges (float32, messages x beams).
RANGES: Path = ("ranges",)


class ColumnarDecoder:
    """The bound fields of a group of CDR messages of ``typename`` at once (module docstring).

    Args:
        store: the rosbags Typestore holding ``typename``.
        typename: the message type (``pkg/msg/Type``).
        paths: the bound field paths (tuples of field names), as the selective decoder takes.

    Raises:
        _NotCovered: a type the walk does not cover (a sequence of strings or messages
            before the end, a field the type lacks, the header time base's stamp).
    """

    def __init__(self, store, typename: str, paths: Iterable[Path]) -> None:
        paths = set(paths)
        if HEADER_STAMP in paths:
            raise _NotCovered("header.stamp is read message by message")
        self.typename = typename
        tree = _tree(store, typename, paths)
        self.program: list[tuple] = []
        self._walk(store, typename, tree, ())
        self.gathered = frozenset(op[2] for op in self.program if op[2] is not None)

    def _walk(self, store, typename: str, tree: dict | None, prefix: Path) -> None:
        for name, desc in store.get_msgdef(typename).fields:
            want = tree is not None and name in tree
            sub = tree.get(name) if tree is not None and want else None
            path = prefix + (name,)
            kind = desc[0]
            if kind == 1 and desc[1][0] == "string":
                self.program.append(("string", 4, None))
            elif kind == 1:
                t = desc[1][0]
                take = want and t in _DTYPE
                self.program.append(("prim", t, path if take else None))
            elif kind == 2:
                self._walk(store, desc[1], sub, path)
            elif kind == 3:
                self._array(store, desc[1], path)
            else:
                elem = desc[1][0]
                if elem[0] != 1 or elem[1][0] == "string":
                    raise _NotCovered("a sequence of strings or messages")
                t = elem[1][0]
                take = want and path == RANGES and typename == _LASER and t == "float32"
                self.program.append(("seq", t, path if take else None))

    def _array(self, store, spec, path: Path) -> None:
        elem, length = spec
        if elem[0] == 1 and elem[1][0] == "string":
            self.program.extend(("string", 4, None) for _ in range(length))
        elif elem[0] == 1:
            self.program.append(("array", elem[1][0], length))
        else:
            for _ in range(length):
                self._walk(store, elem[1], None, path)

    def decode(self, buf: np.ndarray, starts: np.ndarray, lengths: np.ndarray
               ) -> dict[Path, np.ndarray] | None:
        """The gathered columns of the messages ``buf[starts[i]:starts[i] + lengths[i]]``.

        Args:
            buf: uint8 array (a decompressed chunk).
            starts: int64 byte offsets of the messages (their encapsulation header) in ``buf``.
            lengths: int64 lengths of the messages (bytes).

        Returns:
            path -> column (one row per message; see the module docstring), or None when
            some message is not one the selective decoder's fast path reads.
        """
        if len(starts) == 0 or (lengths < 4).any():
            return None
        if (buf[starts] != 0).any() or (buf[starts + 1] != 1).any():
            return None  # not little-endian plain CDR: rosbags decides
        w = _Walk(buf, starts + 4, starts + lengths)
        try:
            for op, t, arg in self.program:
                if not getattr(w, op)(t, arg):
                    return None
        except IndexError:  # pragma: no cover - every read is bounds-checked first
            return None
        end = w.o + w.off - w.base  # relative to the data start
        if ((lengths < end + 4) | (lengths > end + 7)).any():  # at most 3 bytes of padding
            return None
        return w.out


class _Walk:
    """The state of one walk over a group: ``base`` (offset in ``buf`` of each message's data,
    after the encapsulation header), ``o`` + ``off`` (each message's current offset in
    ``buf``: an int64 array plus a constant), ``known`` (``o - base`` is a multiple of it).
    Each method walks one field of every message; False: some message is not read here."""

    def __init__(self, buf: np.ndarray, base: np.ndarray, ends: np.ndarray) -> None:
        self.buf, self.base, self.ends = buf, base, ends
        self.o = base  # absolute offsets in ``buf``; alignment counts from ``base``
        self.off = 0
        self.known = 8
        self.out: dict[Path, np.ndarray] = {}

    def _align(self, a: int) -> None:
        if a <= 1:
            return
        if a <= self.known:
            self.off = (self.off + a - 1) & -a
            return
        rel = self.o - self.base + self.off
        self.o = self.base + ((rel + a - 1) & -a)
        self.off = 0
        self.known = a

    def _inside(self, p: np.ndarray, size: Any) -> bool:
        return not (p + size > self.ends).any()

    def _gather(self, p: np.ndarray, size: int, dtype: str) -> np.ndarray:
        return self.buf[p[:, None] + np.arange(size)].view(dtype)[:, 0]

    def prim(self, t: str, path: Path | None) -> bool:
        size = _SIZE[t]
        self._align(size)
        if path is not None:
            p = self.o + self.off
            if not self._inside(p, size):
                return False
            v = self._gather(p, size, _DTYPE[t])
            self.out[path] = v != 0 if t == "bool" else v.astype(np.float64)
        self.off += size
        return True

    def array(self, t: str, length: int) -> bool:
        self._align(_SIZE[t])
        self.off += length * _SIZE[t]
        return True

    def _count(self) -> np.ndarray | None:
        """The uint32 at each message's current offset (aligned to 4), which is then passed."""
        self._align(4)
        p = self.o + self.off
        if not self._inside(p, 4):
            return None
        n = self._gather(p, 4, "<u4").astype(np.int64)
        self.o, self.off, self.known = p + 4, 0, 1
        return n

    def string(self, _t: Any, _arg: Any) -> bool:
        n = self._count()
        if n is None or (n < 1).any() or not self._inside(self.o, n):
            return False
        if (self.buf[self.o + n - 1] != 0).any():
            return False
        total = int(n.sum())
        if total:
            first = np.repeat(self.o - np.concatenate(([0], np.cumsum(n)[:-1])), n)
            if (self.buf[first + np.arange(total)] >= 0x80).any():
                return False  # not ASCII: the fast path decodes UTF-8; rosbags decides
        self.o = self.o + n
        return True

    def seq(self, t: str, path: Path | None) -> bool:
        n = self._count()
        if n is None:
            return False
        size = _SIZE[t]
        if size > 4:
            rel = self.o - self.base
            self.o = self.base + np.where(n > 0, (rel + size - 1) & -size, rel)
        if not self._inside(self.o, n * size):
            return False
        if path is not None:
            if (n != n[0]).any():
                return False
            self.out[path] = _rows(self.buf, self.o, int(n[0]) * size).view(_DTYPE[t])
        self.o = self.o + n * size
        return True


def _rows(buf: np.ndarray, starts: np.ndarray, width: int) -> np.ndarray:
    """``buf[starts[i]:starts[i] + width]`` as the rows of a uint8 array: a strided view when
    the rows are evenly spaced (messages of one length), else stacked."""
    if len(starts) == 1:
        return buf[int(starts[0]):int(starts[0]) + width][None, :]
    step = np.diff(starts)
    if (step == step[0]).all() and step[0] > 0:
        first = int(starts[0])
        return np.lib.stride_tricks.as_strided(buf[first:], (len(starts), width),
                                               (int(step[0]), 1), writeable=False)
    return np.stack([buf[a:a + width] for a in starts.tolist()])


def columnar_decoder(store: Typestore, typename: str, message_encoding: str, paths: Iterable[Path] | None
                     ) -> ColumnarDecoder | None:
    """A :class:`ColumnarDecoder` of ``typename`` for ``paths``, or None when the walk does not
    cover it (then the messages are decoded one by one). ``message_encoding`` must be
    ``"cdr"``: ROS 1 messages are decoded one by one."""
    if paths is None or message_encoding != "cdr":
        return None
    try:
        return ColumnarDecoder(store, typename, paths)
    except _NotCovered:
        return None


class Segment:
    """Consecutive messages of one topic, as columns beside the messages themselves.

    Args:
        columns: path -> column (:class:`ColumnarDecoder`), or None (only messages).
        n: the number of messages.
        message: ``k -> decoded message`` (the selective decoder's object), called only for
            what the columns do not hold; decoded messages are kept.
        typename: the messages' type.
    """

    __slots__ = ("columns", "n", "_message", "_decoded", "_skip", "typename")

    def __init__(self, columns: dict[Path, np.ndarray] | None, n: int,
                 message: Callable[[int], Any], typename: str, skip: int = 0) -> None:
        self.columns = columns
        self.n = n
        self._message = message
        self._decoded: dict[int, Any] = {}
        self._skip = skip
        self.typename = typename

    def __len__(self) -> int:
        return self.n

    def message(self, k: int) -> Any:
        """The ``k``-th message, decoded (once)."""
        d = self._decoded.get(k)
        if d is None:
            d = self._decoded[k] = self._message(k + self._skip)
        return d

    def dropped(self, k: int) -> Segment:
        """This segment without its first ``k`` messages."""
        cols = None if self.columns is None else {p: c[k:] for p, c in self.columns.items()}
        seg = Segment(cols, self.n - k, self._message, self.typename, self._skip + k)
        seg._decoded = {i - k: d for i, d in self._decoded.items() if i >= k}
        return seg
