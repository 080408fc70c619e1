"""Bus-load arithmetic for the drives' traffic on a classic CAN bus, and the limit the bridge enforces.

A classic frame with an 11-bit id and n data bytes has 47 + 8n bits on the wire (SOF, id, RTR, IDE,
r0, DLC, data, 15-bit CRC, CRC and ACK delimiters, ACK, 7-bit EOF, 3-bit intermission). Bit stuffing
adds one bit after five equal bits in the 34 + 8n bits from SOF to the end of the CRC: at worst
⌊(34 + 8n − 1)/4⌋ bits. Six drives with RPDO1 (4 bytes) + SYNC at 1 kHz and TPDO1 (6 bytes) at
500 Hz need 806 kbit/s (80.6 % of 1 Mbit/s) or 970 kbit/s worst-case stuffed (97.0 %), before
heartbeats (with 10 ms heartbeats: 84.5 % / 101.6 %). :data:`MAX_LOAD` is the limit: the
worst-case (stuffed) load, heartbeats included, must stay at or below 90 %; split the drives over
two channels (3 drives each: 53.8 %) or lower the rates (TPDO1 every 4th SYNC: 84.3 %).

>>> from rss6.can.load import bus_load
>>> one = bus_load(6, bitrate=1_000_000, heartbeat_ms=0, bridge_heartbeat_ms=0)
>>> f"{one.nominal:.1%} {one.worst_case:.1%}"
'80.6% 97.0%'
>>> f"{bus_load(6).worst_case:.1%} {bus_load(3).worst_case:.1%}"  # with 10 ms heartbeats
'101.6% 53.8%'
"""

from __future__ import annotations

from dataclasses import dataclass

from rss6.errors import InvalidInputError

__all__ = ["MAX_LOAD", "BusLoad", "BusLoadError", "bus_load", "check_bus_load", "frame_bits"]

#: Highest worst-case (stuffed) bus load the bridge accepts on a bus with a known bitrate.
MAX_LOAD = 0.90


class BusLoadError(InvalidInputError):
    """A configuration needs more of the bus than :data:`MAX_LOAD`."""


def frame_bits(dlc: int, *, stuffed: bool = False) -> int:
    """Bits on the wire of one classic base-format (11-bit id) data frame with ``dlc`` bytes;
    ``stuffed``: with the worst-case number of stuff bits."""
    if not 0 <= dlc <= 8:
        raise InvalidInputError(f"a classic CAN frame has 0..8 data bytes, got {dlc}")
    bits = 47 + 8 * dlc
    if stuffed:
        bits += (34 + 8 * dlc - 1) // 4
    return bits


@dataclass(frozen=True)
class BusLoad:
    """Load of one channel: bits per second without (``nominal_bps``) and with worst-case stuffing
    (``worst_case_bps``), and as fractions of ``bitrate``. ``items``: (name, frames/s, bytes)."""

    bitrate: int
    nominal_bps: float
    worst_case_bps: float
    items: tuple[tuple[str, float, int], ...]

    @property
    def nominal(self) -> float:
        """Load without stuff bits (fraction of the bitrate)."""
        return self.nominal_bps / self.bitrate

    @property
    def worst_case(self) -> float:
        """Load with worst-case stuffing (fraction of the bitrate)."""
        return self.worst_case_bps / self.bitrate

    def table(self) -> str:
        """A printable breakdown (docs/can.md shows it)."""
        lines = [f"{'frame':<22}{'frames/s':>10}{'bytes':>7}{'kbit/s':>9}{'stuffed':>9}"]
        for name, rate, dlc in self.items:
            lines.append(
                f"{name:<22}{rate:>10.0f}{dlc:>7d}{rate * frame_bits(dlc) / 1e3:>9.1f}"
                f"{rate * frame_bits(dlc, stuffed=True) / 1e3:>9.1f}"
            )
        lines.append(
            f"{'total':<22}{'':>10}{'':>7}{self.nominal_bps / 1e3:>9.1f}"
            f"{self.worst_case_bps / 1e3:>9.1f}   = {100 * self.nominal:.1f} % / "
            f"{100 * self.worst_case:.1f} % of {self.bitrate / 1e6:g} Mbit/s"
        )
        return "\n".join(lines)


def bus_load(
    drives: int,
    *,
    bitrate: int = 1_000_000,
    sync_hz: float = 1000.0,
    tpdo_every: int = 2,
    heartbeat_ms: int = 10,
    bridge_heartbeat_ms: int = 10,
) -> BusLoad:
    """Load of one channel carrying ``drives`` drives: an RPDO1 per drive and a SYNC per cycle,
    a TPDO1 per drive every ``tpdo_every`` SYNCs, a heartbeat per drive every ``heartbeat_ms`` and
    the bridge's every ``bridge_heartbeat_ms`` (0: none). RPDO2, SDO and EMCY are event traffic
    and not counted."""
    if drives < 1 or bitrate <= 0 or sync_hz <= 0 or tpdo_every < 1:
        raise InvalidInputError("bus_load: drives, bitrate, sync_hz and tpdo_every must be >= 1")
    items: list[tuple[str, float, int]] = [
        ("RPDO1 target", drives * sync_hz, 4),
        ("SYNC", sync_hz, 0),
        ("TPDO1 status+position", drives * sync_hz / tpdo_every, 6),
    ]
    if heartbeat_ms > 0:
        items.append(("heartbeat drives", drives * 1000.0 / heartbeat_ms, 1))
    if bridge_heartbeat_ms > 0:
        items.append(("heartbeat bridge", 1000.0 / bridge_heartbeat_ms, 1))
    nominal = sum(rate * frame_bits(dlc) for _, rate, dlc in items)
    worst = sum(rate * frame_bits(dlc, stuffed=True) for _, rate, dlc in items)
    return BusLoad(bitrate, nominal, worst, tuple(items))


def check_bus_load(load: BusLoad, max_load: float = MAX_LOAD) -> BusLoad:
    """Returns ``load`` if its worst-case fraction is at most ``max_load``, else raises
    :class:`BusLoadError` naming the fix."""
    if load.worst_case > max_load:
        raise BusLoadError(
            f"the drives need {100 * load.worst_case:.1f} % of the {load.bitrate / 1e6:g} Mbit/s "
            f"bus with worst-case bit stuffing ({100 * load.nominal:.1f} % without), above the "
            f"{100 * max_load:.0f} % limit: split the drives over two channels (channels=2) or "
            "lower the rates (tpdo_every, sync period)"
        )
    return load
