"""LCM event-log files (the format lcm-logger writes and lcm-logplayer reads).

Debian ships no Python binding for LCM, so the tools read and write logs
themselves. Layout of one event, all integers big-endian:

    uint32 sync (0xEDA1DA01) | int64 event number | int64 timestamp (us)
    int32 channel length | int32 data length | channel bytes | data bytes

The channel is not NUL-terminated. Event numbers start at 0 and grow by one.
"""

import os
import struct
from typing import BinaryIO, Iterator, NamedTuple, Optional, Union

SYNC_WORD = 0xEDA1DA01
_HEADER = struct.Struct(">Iqqii")
HEADER_SIZE = _HEADER.size  # 28

# LCM refuses to publish on longer channel names, so a log holding one could
# be read but never replayed; reject it when writing.
MAX_CHANNEL_LENGTH = 63

# lcm's own reader gives up on absurd lengths (a sign of a corrupt header)
# instead of trying to allocate them; do the same.
_MAX_READ_CHANNEL_LENGTH = 1000
_MAX_DATA_LENGTH = 1 << 30

PathLike = Union[str, "os.PathLike[str]"]


class LcmLogError(ValueError):
    """A log file that is not a well-formed LCM event log."""


class LogEvent(NamedTuple):
    eventnum: int
    timestamp: int  # microseconds
    channel: str
    data: bytes


class LogWriter:
    """Appends events to a new log file; event numbers are assigned here."""

    def __init__(self, path_or_file: Union[PathLike, BinaryIO]):
        if hasattr(path_or_file, "write"):
            self._f = path_or_file
            self._owns = False
        else:
            self._f = open(path_or_file, "wb")
            self._owns = True
        self.count = 0

    def write(self, channel: str, data: bytes, timestamp: int) -> int:
        """Write one event; returns its event number."""
        chan = channel.encode("utf-8")
        if not chan:
            raise ValueError("LCM channel name must not be empty")
        if len(chan) > MAX_CHANNEL_LENGTH:
            raise ValueError(
                f"LCM channel name {channel!r} is {len(chan)} bytes; "
                f"LCM allows at most {MAX_CHANNEL_LENGTH}")
        data = bytes(data)
        if len(data) > _MAX_DATA_LENGTH:
            raise ValueError(f"event data of {len(data)} bytes is too large")
        eventnum = self.count
        self._f.write(_HEADER.pack(SYNC_WORD, eventnum, int(timestamp),
                                   len(chan), len(data)))
        self._f.write(chan)
        self._f.write(data)
        self.count += 1
        return eventnum

    def close(self) -> None:
        if self._owns:
            self._f.close()
        else:
            self._f.flush()

    def __enter__(self) -> "LogWriter":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _read_exact(f: BinaryIO, n: int) -> bytes:
    parts = []
    while n > 0:
        chunk = f.read(n)
        if not chunk:
            break
        parts.append(chunk)
        n -= len(chunk)
    return b"".join(parts)


class LogReader:
    """Iterates over the events of a log, strictly.

    A short or corrupt event raises LcmLogError naming the event (its index in
    the file) and the byte offset where it starts. lcm-logger killed mid-write
    leaves a truncated last event; pass allow_truncated_tail=True to stop
    quietly there instead (a bad sync word is still an error).
    """

    def __init__(self, path_or_file: Union[PathLike, BinaryIO],
                 allow_truncated_tail: bool = False):
        if hasattr(path_or_file, "read"):
            self._f = path_or_file
            self._owns = False
            self.name = getattr(path_or_file, "name", "<stream>")
        else:
            self._f = open(path_or_file, "rb")
            self._owns = True
            self.name = os.fspath(path_or_file)
        self.allow_truncated_tail = allow_truncated_tail
        self.truncated = False

    def __iter__(self) -> Iterator[LogEvent]:
        index = 0
        offset = self._f.tell()
        while True:
            ev = self._read_one(index, offset)
            if ev is None:
                return
            yield ev
            offset += HEADER_SIZE + len(ev.channel.encode("utf-8")) + len(ev.data)
            index += 1

    def _truncated(self, index: int, offset: int, what: str) -> None:
        if self.allow_truncated_tail:
            self.truncated = True
            return None
        raise LcmLogError(
            f"{self.name}: truncated event {index} at byte offset {offset}: {what}")

    def _read_one(self, index: int, offset: int) -> Optional[LogEvent]:
        head = _read_exact(self._f, HEADER_SIZE)
        if not head:
            return None
        if len(head) < HEADER_SIZE:
            return self._truncated(
                index, offset, f"header has {len(head)} of {HEADER_SIZE} bytes")
        sync, eventnum, timestamp, chan_len, data_len = _HEADER.unpack(head)
        if sync != SYNC_WORD:
            raise LcmLogError(
                f"{self.name}: event {index} at byte offset {offset}: bad sync "
                f"word 0x{sync:08X} (expected 0x{SYNC_WORD:08X}); not an LCM log "
                "or corrupt")
        if not 0 < chan_len <= _MAX_READ_CHANNEL_LENGTH:
            raise LcmLogError(
                f"{self.name}: event {index} at byte offset {offset}: "
                f"implausible channel length {chan_len}")
        if not 0 <= data_len <= _MAX_DATA_LENGTH:
            raise LcmLogError(
                f"{self.name}: event {index} at byte offset {offset}: "
                f"implausible data length {data_len}")
        chan = _read_exact(self._f, chan_len)
        if len(chan) < chan_len:
            return self._truncated(
                index, offset, f"channel has {len(chan)} of {chan_len} bytes")
        data = _read_exact(self._f, data_len)
        if len(data) < data_len:
            return self._truncated(
                index, offset, f"data has {len(data)} of {data_len} bytes")
        try:
            channel = chan.decode("utf-8")
        except UnicodeDecodeError as e:
            raise LcmLogError(
                f"{self.name}: event {index} at byte offset {offset}: "
                f"channel is not UTF-8 ({e})") from None
        return LogEvent(eventnum, timestamp, channel, data)

    def close(self) -> None:
        if self._owns:
            self._f.close()

    def __enter__(self) -> "LogReader":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def read_events(path: PathLike, allow_truncated_tail: bool = False) -> list:
    """All events of a log as a list."""
    with LogReader(path, allow_truncated_tail) as r:
        return list(r)
