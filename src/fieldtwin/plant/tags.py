"""Tags: a plant file's names for what its objects mean (docs/plant.md, "Tags").

A ``[[tag]]`` table names one source - a PL7 object (``object = "W0"``, ``"O16,3"``,
``"IW5,3"``) or one input, output or register of a device (``device = "tes1"`` with
``input = "3"``, ``output = "a4"`` or ``register = "H'005'"``; ``device = "5"`` with
``input = "2"`` is the AEM's channel 2, its own measurement, never a multiplexed
word) - with a label (``name``), a ``unit``, a linear ``scale`` (``[raw_lo, raw_hi,
eng_lo, eng_hi]``) and a ``description``.  ``[dashboard] trends`` lists the series
the dashboard opens with (tags or objects).

The tags are a plain value on the plant (``plant.tags``), checked against the
built plant once: an unknown object, device, input, output or register, a name
that clashes, a bad scale, each names its plant-file field and what is allowed.
Their values are read through the Device face and the PLC's object reads only,
without side effects (a TES register is peeked): :func:`tag_value`.

A scenario or a script resolves a name with :func:`resolve` (a tag, or an object
the PLC knows): it gives the :class:`Tag` (a bare object gets a tag of its own
name), whose ``source`` says where to read, set or write.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal, Protocol

from fieldtwin.devices.face import Device, Family, device_id
from fieldtwin.errors import ConfigError, refuse_unknown_keys
from fieldtwin.words import parse_word

if TYPE_CHECKING:
    from fieldtwin.tsx.plc import Plc


class Plant(Protocol):
    """What the tags read of a plant (fieldtwin.plant.value.Plant; named here by its
    shape, so that the plant's value and its tags import in one direction only)."""

    @property
    def plc(self) -> Plc | None: ...

    @property
    def devices(self) -> Sequence[Device]: ...

    @property
    def tags(self) -> Tags: ...


TAG_KEYS = (
    "name",
    "unit",
    "scale",
    "description",
    "object",
    "device",
    "input",
    "output",
    "register",
)
DEVICE_KEYS = ("input", "output", "register")
DASHBOARD_KEYS = ("trends",)
MAX_TAGS = 1024  # a plant file's tags (each is read for GET /tags: bounded)
MAX_TRENDS = 16  # default trends of [dashboard]
MAX_NAME = 64
MAX_TEXT = 256  # a unit or a description
NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_.\-]*$")
# what a PL7 object or an internal object looks like: a tag name may not (``read W0``)
_OBJECT_RE = re.compile(r"^(IW|OW|CW|SW|SY|TXT|I|O|W|B|X|T|C|M)\d", re.IGNORECASE)

Kind = Literal["object", "input", "output", "register"]
TagNumber = bool | int | float


@dataclass(frozen=True, slots=True)
class Scale:
    """Linear raw -> engineering: ``raw_lo`` reads ``eng_lo``, ``raw_hi`` reads ``eng_hi``."""

    raw_lo: float
    raw_hi: float
    eng_lo: float
    eng_hi: float

    def apply(self, raw: float) -> float:
        ratio = (raw - self.raw_lo) / (self.raw_hi - self.raw_lo)
        return self.eng_lo + ratio * (self.eng_hi - self.eng_lo)

    def as_list(self) -> list[float]:
        return [self.raw_lo, self.raw_hi, self.eng_lo, self.eng_hi]


@dataclass(frozen=True, slots=True)
class TagSource:
    """Where a tag's value is: a PL7 object (``device`` None), or a device's input,
    output or register (``name``: the input's or output's name, the register's address)."""

    kind: Kind
    name: str
    device: str | None = None

    @property
    def text(self) -> str:
        """``W0``, ``tes1 input 3``, ``tes1 register H'005'``: as the API and console show it."""
        if self.device is None:
            return self.name
        return f"{self.device} {self.kind} {self.name}"

    def json(self) -> dict[str, str]:
        if self.device is None:
            return {"object": self.name}
        return {"device": self.device, self.kind: self.name}


@dataclass(frozen=True, slots=True)
class Tag:
    """One ``[[tag]]``: its name, source, unit, scale and description."""

    name: str
    source: TagSource
    unit: str = ""
    scale: Scale | None = None
    description: str = ""
    where: str = ""  # its field path in the plant file ("plant.toml: tag[2]")


@dataclass(frozen=True, slots=True)
class TagValue:
    """A tag's value now: ``value`` in its unit (scaled), ``raw`` as the source gives it;
    both None where the source has nothing to show (an inhibited channel, a TES off)."""

    tag: Tag
    value: TagNumber | None
    raw: TagNumber | None
    unit: str

    @property
    def text(self) -> str:
        """``4500 mm``, ``on``, ``12.5 l/min``, ``-``: as a person reads it."""
        return value_text(self.value, self.unit)

    def json(self) -> dict[str, object]:
        tag = self.tag
        out: dict[str, object] = {
            "name": tag.name,
            "source": tag.source.json(),
            "source_text": tag.source.text,
            "unit": self.unit,
            "description": tag.description,
            "value": self.value,
            "raw": self.raw,
            "text": self.text,
        }
        if tag.scale is not None:
            out["scale"] = tag.scale.as_list()
        return out


def value_text(value: TagNumber | None, unit: str = "") -> str:
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "on" if value else "off"
    if isinstance(value, float):
        shown = f"{value:.4g}" if abs(value) < 1e4 else f"{value:.0f}"
    else:
        shown = str(value)
    return f"{shown} {unit}" if unit else shown


@dataclass(frozen=True, slots=True)
class Tags:
    """A plant's tags by name, in file order, and the dashboard's default trends."""

    tags: tuple[Tag, ...] = ()
    trends: tuple[str, ...] = ()
    _by_name: Mapping[str, Tag] = field(default_factory=dict, repr=False, compare=False)
    _by_source: Mapping[tuple[str | None, str, str], Tag] = field(
        default_factory=dict, repr=False, compare=False
    )

    @classmethod
    def of(cls, tags: Sequence[Tag], trends: Sequence[str] = ()) -> Tags:
        by_source: dict[tuple[str | None, str, str], Tag] = {}
        for tag in tags:
            by_source.setdefault(_source_key(tag.source), tag)
        return cls(tuple(tags), tuple(trends), {t.name.lower(): t for t in tags}, by_source)

    def __iter__(self) -> Iterator[Tag]:
        return iter(self.tags)

    def __len__(self) -> int:
        return len(self.tags)

    def __bool__(self) -> bool:
        return bool(self.tags)

    def get(self, name: str) -> Tag | None:
        """The tag named ``name`` (case-insensitive), or None."""
        return self._by_name.get(name.strip().lower())

    def named(self, name: str) -> Tag:
        """The tag named ``name``; an unknown name lists the tags (answered 404 by the API)."""
        found = self.get(name)
        if found is None:
            raise UnknownTag(f"no tag {name!r} (allowed: {self.allowed()})")
        return found

    def allowed(self) -> str:
        names = [t.name for t in self.tags]
        shown = ", ".join(names[:20]) + (f", ... ({len(names)} tags)" if len(names) > 20 else "")
        return shown or "none: this plant file has no [[tag]] table"

    def of_object(self, name: str) -> Tag | None:
        """The tag of the PL7 object ``name`` (``W0``, ``O16,3``), if one has it."""
        return self._by_source.get((None, "object", _object_key(name)))

    def of_device(self, device: str, kind: Kind, name: str) -> Tag | None:
        """The tag of a device's input, output or register, if one has it."""
        return self._by_source.get((device, kind, name.strip().lower()))


class UnknownTag(ConfigError):
    """An unknown tag name (the control API answers it 404)."""


def _object_key(name: str) -> str:
    return "".join(name.split()).upper()


def _source_key(source: TagSource) -> tuple[str | None, str, str]:
    if source.device is None:
        return (None, "object", _object_key(source.name))
    return (source.device, source.kind, source.name.strip().lower())


# --------------------------------------------------------------- reading the plant file


def read_tags(data: Mapping[str, object], name: str, plant: Plant) -> Tags:
    """``[[tag]]`` and ``[dashboard]`` of a plant file, checked against the built plant."""
    tables = data.get("tag", [])
    if not isinstance(tables, list):
        raise ConfigError(f"{name}: tag must be an array of tables ([[tag]])")
    if len(tables) > MAX_TAGS:
        raise ConfigError(f"{name}: tag: {len(tables)} tags (allowed at most {MAX_TAGS})")
    devices = {device_id(d, plant.devices): d for d in plant.devices}
    tags: list[Tag] = []
    seen: dict[str, str] = {}
    for index, table in enumerate(tables):
        where = f"{name}: tag[{index}]"
        tag = _tag(table, where, plant, devices)
        key = tag.name.lower()
        if key in seen:
            raise ConfigError(
                f"{where}.name: {tag.name!r} is already the name of {seen[key]}"
                " (allowed: a name no other tag has; names are case-insensitive)"
            )
        seen[key] = where.split(": ", 1)[-1]
        tags.append(tag)
    trends = _trends(data, name, plant, {t.name.lower() for t in tags})
    return Tags.of(tags, trends)


def _tag(table: object, where: str, plant: Plant, devices: Mapping[str, Device]) -> Tag:
    if not isinstance(table, Mapping):
        raise ConfigError(f"{where}: must be a table ([[tag]] with name and object or device)")
    refuse_unknown_keys(table, TAG_KEYS, where)
    tag_name = _name(table.get("name"), f"{where}.name", devices)
    unit = _text(table.get("unit", ""), f"{where}.unit")
    description = _text(table.get("description", ""), f"{where}.description")
    source = _source(table, where, plant, devices)
    scale = _scale(table.get("scale"), f"{where}.scale")
    if scale is not None and _is_bit(source, plant):
        raise ConfigError(
            f"{where}.scale: {source.text} is a bit (on/off): a scale is for a number"
            " (allowed: no scale on a bit)"
        )
    return Tag(tag_name, source, unit, scale, description, where)


def _name(value: object, where: str, devices: Mapping[str, Device]) -> str:
    if not isinstance(value, str) or not value:
        raise ConfigError(
            f'{where}: missing or not a string (allowed: a name such as "tank1.level")'
        )
    if len(value) > MAX_NAME or not NAME_RE.match(value):
        raise ConfigError(
            f"{where}: {value!r} not allowed (allowed: a letter or _ then letters, digits,"
            f" '.', '_' or '-', at most {MAX_NAME} characters)"
        )
    if _OBJECT_RE.match(value):
        raise ConfigError(
            f"{where}: {value!r} reads as a PL7 object (allowed: a name that is no object,"
            ' e.g. "tank1.level")'
        )
    if value.lower() in {d.lower() for d in devices}:
        raise ConfigError(
            f"{where}: {value!r} is a device's id (allowed: a name that is no device id)"
        )
    return value


def _text(value: object, where: str) -> str:
    if not isinstance(value, str) or len(value) > MAX_TEXT:
        raise ConfigError(
            f"{where}: {value!r} not allowed (allowed: a string of at most {MAX_TEXT} characters)"
        )
    return value


def _number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _scale(value: object, where: str) -> Scale | None:
    if value is None:
        return None
    if not isinstance(value, list) or len(value) != 4 or not all(_number(v) for v in value):
        raise ConfigError(
            f"{where}: {value!r} not allowed (allowed: four numbers [raw_lo, raw_hi, eng_lo,"
            " eng_hi], e.g. [0, 20000, 0, 20])"
        )
    raw_lo, raw_hi, eng_lo, eng_hi = (float(v) for v in value)
    for lo, hi, a, b in (
        ("raw_lo", "raw_hi", raw_lo, raw_hi),
        ("eng_lo", "eng_hi", eng_lo, eng_hi),
    ):
        if a == b:
            raise ConfigError(
                f"{where}: {lo} and {hi} are both {a:g} (allowed: two different values)"
            )
    return Scale(raw_lo, raw_hi, eng_lo, eng_hi)


def _source(
    table: Mapping[str, object], where: str, plant: Plant, devices: Mapping[str, Device]
) -> TagSource:
    has_object, has_device = "object" in table, "device" in table
    given = [k for k in DEVICE_KEYS if k in table]
    if has_object == has_device:
        raise ConfigError(
            f'{where}: give either object (a PL7 object such as "W0") or device (with one'
            f" of {', '.join(DEVICE_KEYS)}), not {'both' if has_object else 'neither'}"
        )
    if has_object:
        if given:
            raise ConfigError(
                f"{where}.{given[0]}: goes with device, not object (allowed with object: none)"
            )
        return TagSource("object", _pl7_object(table["object"], f"{where}.object", plant))
    ident = table["device"]
    if not isinstance(ident, str) or ident not in devices:
        raise ConfigError(
            f"{where}.device: {ident!r} not allowed (allowed: {', '.join(devices) or 'none'})"
        )
    if len(given) != 1:
        raise ConfigError(
            f"{where}: device {ident} takes one of input, output or register"
            f" ({'none' if not given else ' and '.join(given)} given; allowed: exactly one)"
        )
    kind = given[0]
    device = devices[ident]
    value = table[kind]
    if isinstance(value, int) and not isinstance(value, bool):
        value = str(value)
    if not isinstance(value, str) or not value.strip():
        raise ConfigError(f'{where}.{kind}: {value!r} is not a name (e.g. {kind} = "3")')
    at = f"{where}.{kind}"
    if kind == "input":
        names = list(device.inputs())
        found = _pick(names, value)
    elif kind == "output":
        names = list(device.outputs())
        found = _pick(names, value)
    else:
        names = [e.address for e in device.objects().names()]
        found = _register(device, value)
    if found is None:
        from fieldtwin.devices.face import allowed_names

        listed = allowed_names(names) if kind != "register" else _registers_allowed(device)
        raise ConfigError(
            f"{at}: {value!r} is no {kind} of {device.kind} {ident} (allowed: {listed})"
        )
    return TagSource(kind, found, ident)  # type: ignore[arg-type]


def _pick(names: Sequence[str], value: str) -> str | None:
    token = value.strip()
    for name in names:
        if name == token or name.lower() == token.lower():
            return name
    return None


def _register(device: Device, value: str) -> str | None:
    """The register's address as the device's objects list it (``H'005'``)."""
    token = value.strip()
    entries = device.objects().names()
    for entry in entries:
        if token.lower() in (entry.address.lower(), entry.name.lower()):
            return entry.address
    try:
        number = parse_word(token)
    except ConfigError:
        return None
    for entry in entries:
        try:
            if parse_word(entry.address) == number:
                return entry.address
        except ConfigError:
            continue
    return None


def _registers_allowed(device: Device) -> str:
    entries = device.objects().names()
    shown = [e.text for e in entries[:8]]
    more = f", ... ({len(entries)} registers: GET /devices/ID/objects)" if len(entries) > 8 else ""
    return ", ".join(shown) + more if shown else "none"


def _pl7_object(value: object, where: str, plant: Plant) -> str:
    plc = plant.plc
    if plc is None:
        raise ConfigError(
            f"{where}: {value!r}: this plant has no PLC (allowed: device = ... with input,"
            " output or register)"
        )
    if not isinstance(value, str) or not value.strip():
        raise ConfigError(f'{where}: {value!r} is not a PL7 object (e.g. "W0", "IW5,3", "O16,3")')
    try:
        plc.read(value)
    except ConfigError as exc:
        raise ConfigError(f"{where}: {exc}") from None
    return _canonical(value)


def _canonical(name: str) -> str:
    """``iw5,3`` -> ``IW5,3``, ``w0`` -> ``W0``: as the console writes an object."""
    from fieldtwin.tsx.addressing import format_object, parse_object

    text = "".join(name.split())
    if text.upper().startswith(("W", "B", "X", "CW", "SY", "SW")):
        return text.upper()
    try:
        return format_object(parse_object(text))
    except ConfigError:
        return text.upper()


def _is_bit(source: TagSource, plant: Plant) -> bool:
    if source.kind != "object":
        return False
    return _object_is_bit(source.name)


def _object_is_bit(name: str) -> bool:
    from fieldtwin.tsx.addressing import parse_object

    upper = name.upper()
    if upper.startswith(("B", "SY", "X")):
        return True
    if upper.startswith(("W", "CW", "SW")):
        return False
    try:
        return parse_object(name).is_bit
    except ConfigError:
        return False


def _trends(data: Mapping[str, object], name: str, plant: Plant, tags: set[str]) -> tuple[str, ...]:
    table = data.get("dashboard", {})
    if not isinstance(table, Mapping):
        raise ConfigError(f"{name}: dashboard must be a table ([dashboard])")
    unknown = sorted(set(table) - set(DASHBOARD_KEYS))
    if unknown:
        raise ConfigError(
            f"{name}: dashboard: unknown key(s) {', '.join(unknown)}"
            f" (allowed: {', '.join(DASHBOARD_KEYS)})"
        )
    trends = table.get("trends", [])
    where = f"{name}: dashboard.trends"
    if not isinstance(trends, list) or len(trends) > MAX_TRENDS:
        raise ConfigError(
            f'{where}: a list of at most {MAX_TRENDS} tags or objects, e.g. ["tank1.level", "W4"]'
        )
    out: list[str] = []
    for index, series in enumerate(trends):
        if not isinstance(series, str) or not series.strip():
            raise ConfigError(f"{where}[{index}]: {series!r} is not a tag or an object")
        if series.strip().lower() in tags:
            out.append(series.strip())
            continue
        if plant.plc is not None:
            try:
                plant.plc.read(series)
            except ConfigError:
                pass
            else:
                out.append(series.strip().upper())
                continue
        allowed = ", ".join(sorted(tags)) or "none"
        raise ConfigError(
            f"{where}[{index}]: {series!r} is no tag of this plant nor a PL7 object"
            f" (allowed: a tag - {allowed} - or an object such as W0)"
        )
    return tuple(out)


# --------------------------------------------------------------- values, through the face


def resolve(plant: Plant, name: str) -> Tag:
    """A tag by name, or a PL7 object the plant's PLC reads (``W0``, ``IW5,2,0``) as a tag
    of its own name (its own tag if one names it): what a scenario's ``tag`` or
    ``object`` refers to.  ConfigError (UnknownTag) naming what is allowed."""
    found = plant.tags.get(name)
    if found is not None:
        return found
    plc = plant.plc
    if plc is not None and name.strip():
        try:
            plc.read(name)
        except ConfigError:
            pass
        else:
            tagged = plant.tags.of_object(name)
            if tagged is not None:
                return tagged
            canonical = _canonical(name)
            return Tag(canonical, TagSource("object", canonical))
    raise UnknownTag(
        f"no tag {name!r} (allowed: {plant.tags.allowed()}"
        + (", or a PL7 object such as W0 or IW5,3" if plc is not None else "")
        + ")"
    )


def tag_value(plant: Plant, tag: Tag) -> TagValue:
    """The tag's value now, read without side effects, scaled into its unit."""
    raw, unit = _raw(plant, tag.source)
    value: TagNumber | None = raw
    if tag.scale is not None and raw is not None and not isinstance(raw, bool):
        value = round(tag.scale.apply(float(raw)), 6)
    return TagValue(tag, value, raw, tag.unit or unit)


def raw_value(tag: Tag, value: float) -> float:
    """A number in the tag's unit, back to the source's (the scale's inverse)."""
    scale = tag.scale
    if scale is None:
        return value
    ratio = (value - scale.eng_lo) / (scale.eng_hi - scale.eng_lo)
    return scale.raw_lo + ratio * (scale.raw_hi - scale.raw_lo)


def raw_word(tag: Tag, value: float) -> int:
    """A number in the tag's unit as the raw word its object or register takes."""
    number = round(raw_value(tag, value))
    if not -32768 <= number <= 0xFFFF:
        raise ConfigError(
            f"tag {tag.name}: {value:g} {tag.unit} is {number} raw, not a word"
            " (allowed -32768..65535 raw)"
        )
    return number & 0xFFFF if number < 0 else number


def read_value(plant: Plant, name: str) -> TagValue:
    """``resolve(plant, name)``'s value now."""
    return tag_value(plant, resolve(plant, name))


def _device(plant: Plant, ident: str) -> Device:
    for device in plant.devices:
        if device_id(device, plant.devices) == ident:
            return device
    raise ConfigError(f"no device {ident!r} in this plant")


def _raw(plant: Plant, source: TagSource) -> tuple[TagNumber | None, str]:
    if source.device is None:
        plc = plant.plc
        if plc is None:
            return None, ""
        return _object_value(plc, source.name), ""
    device = _device(plant, source.device)
    if source.kind == "output":
        out = device.outputs()[source.name].read()
        return out.value, out.unit
    if source.kind == "register":
        return device.objects().peek(source.name), ""
    return _input_value(plant, device, source.name)


def _object_value(plc: Plc, name: str) -> TagNumber:
    if _object_is_bit(name):
        return bool(plc.read(name))
    try:
        return plc.read_signed(name)  # a PL7 word is a signed 16-bit integer
    except ConfigError:
        return plc.read(name)


def _input_value(plant: Plant, device: Device, name: str) -> tuple[TagNumber | None, str]:
    """An input as the device's front shows it: a measurement (an AEM channel in its
    configured scaling, a TES analog input in volts), or a contact (a TES's input
    bits, a discrete module's Ixy,i); None where the front shows nothing of it."""
    panel = device.panel()
    for reading in panel.readings:
        if reading.name == name:
            return reading.value, reading.unit
    row = panel.row("in")
    if row and name.isdigit() and int(name) < len(row):
        return row[int(name)], ""
    # a plain discrete input module (its points, its I bits shown): input i is Ixy,i
    module = getattr(device, "module", None)
    points = getattr(module, "points", None)
    if (
        device.family is Family.MODULE
        and plant.plc is not None
        and isinstance(points, int)
        and getattr(module, "shows_i_bits", False)
    ):
        return bool(plant.plc.read(f"I{device.address},{name}")), ""
    return None, ""


__all__ = [
    "DASHBOARD_KEYS",
    "MAX_TAGS",
    "MAX_TRENDS",
    "TAG_KEYS",
    "Scale",
    "Tag",
    "TagSource",
    "TagValue",
    "Tags",
    "UnknownTag",
    "raw_value",
    "raw_word",
    "read_tags",
    "read_value",
    "resolve",
    "tag_value",
    "value_text",
]
