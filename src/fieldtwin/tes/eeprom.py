"""Checks across parameters (what TESIS refuses) and the MP image loaded at power-on."""

from __future__ import annotations

from collections.abc import Iterator, Mapping

from fieldtwin.errors import ConfigError
from fieldtwin.tes.models import Family, TesModel
from fieldtwin.tes.params import DAC_MAX, NO_OUTPUT, POINTS_MAX, Value, complete


def _int(values: Mapping[str, Value], name: str) -> int:
    value = values[name]
    assert isinstance(value, int), name
    return value


def final_range(values: Mapping[str, Value], k: int) -> tuple[int, int]:
    """§4.2.4: the span of analog input k's final value (points when not scaled)."""
    if values[f"ai{k}.scale"] != "on":
        return 0, POINTS_MAX
    a, b = _int(values, f"ai{k}.scale_min"), _int(values, f"ai{k}.scale_max")
    return min(a, b), max(a, b)


def _threshold_problems(values: Mapping[str, Value], k: int) -> Iterator[str]:
    kind = values[f"ai{k}.threshold"]
    if kind == "none":
        return
    p = f"ai{k}."
    low, high = _int(values, p + "low"), _int(values, p + "high")
    lo, hi = final_range(values, k)
    # §4.2.6 "If thresholds are put on an incorrect value for the final value, « overloaded »"
    for name, value in (("low", low), ("high", high)):
        if not lo <= value <= hi:
            yield f"{p}{name}: {value} overloaded (allowed {lo}..{hi}, the final value range)"
    if low >= high:
        yield f"{p}low: {low} must be below {p}high ({high})"
    out_low, out_high = _int(values, p + "out_low"), _int(values, p + "out_high")
    if kind == "simple" and (out_low, out_high) != (NO_OUTPUT, NO_OUTPUT):
        yield f"{p}threshold: simple thresholds have no output (set {p}out_low/out_high to -1)"
    if kind == "hysteresis" and (out_high == NO_OUTPUT or out_low not in (NO_OUTPUT, out_high)):
        yield f"{p}out_high: hysteresis needs one reflex output 0..3 (out_low -1 or the same)"
    if kind == "high_low" and (NO_OUTPUT in (out_low, out_high) or out_low == out_high):
        yield f"{p}out_low: high/low thresholds need two different outputs 0..3 (§4.2.6.3)"


def _scale_problems(values: Mapping[str, Value], prefix: str, count_name: str) -> Iterator[str]:
    if (
        values[prefix + "scale"] == "on"
        and values[prefix + "scale_min"] == values[prefix + "scale_max"]
    ):
        yield f"{prefix}scale_max: must differ from {prefix}scale_min ({count_name})"


def _output_users(model: TesModel, values: Mapping[str, Value]) -> Iterator[str]:
    # §4.2.6.2 "Don't choose the same digital output for 2 different analog inputs!"
    used: dict[int, int] = {}
    for k in model.analog_inputs:
        if values[f"ai{k}.threshold"] in ("hysteresis", "high_low"):
            for out in {_int(values, f"ai{k}.out_low"), _int(values, f"ai{k}.out_high")} - {-1}:
                if out in used:
                    yield f"ai{k}.out: output {out} is already driven by ai{used[out]}"
                used[out] = k


def problems(model: TesModel, values: Mapping[str, Value]) -> list[str]:
    """Every reason TESIS would refuse this configuration ([] when valid)."""
    found: list[str] = []
    for k in model.analog_inputs:
        found += _scale_problems(values, f"ai{k}.", "§4.2.4")
        found += _threshold_problems(values, k)
    for k in model.analog_outputs:
        found += _scale_problems(values, f"ao{k}.", "§4.3.1")
        value, (lo, hi) = _int(values, f"ao{k}.fallback"), ao_range(values, k)
        if not lo <= value <= hi:
            found.append(f"ao{k}.fallback: {value} out of range (allowed {lo}..{hi})")
    found += _output_users(model, values)
    return found


def ao_range(values: Mapping[str, Value], k: int) -> tuple[int, int]:
    if values[f"ao{k}.scale"] != "on":
        return 0, DAC_MAX
    a, b = _int(values, f"ao{k}.scale_min"), _int(values, f"ao{k}.scale_max")
    return min(a, b), max(a, b)


def checked(model: TesModel, values: Mapping[str, object]) -> dict[str, Value]:
    """Complete and validate, or ConfigError listing every problem."""
    full = complete(model, values)
    found = problems(model, full)
    if found:
        raise ConfigError(f"{model.name}: invalid parameters: " + "; ".join(found))
    return full


# --- MP image (§6) -----------------------------------------------------------


def _u16(value: int) -> int:
    return value & 0xFFFF


def _threshold_words(values: Mapping[str, Value], k: int) -> tuple[int, int, int]:
    """(low, high, outputs) words of analog input k (AMB-TES-21: high byte = high threshold)."""
    kind = values[f"ai{k}.threshold"]
    if kind == "none":
        return 0x8000, 0x7FFF, 0xFFFF  # never crossed, no output
    low, high = _u16(_int(values, f"ai{k}.low")), _u16(_int(values, f"ai{k}.high"))
    out_low, out_high = (
        _int(values, f"ai{k}.out_low") & 0xFF,
        _int(values, f"ai{k}.out_high") & 0xFF,
    )
    if kind == "simple":
        return low, high, 0xFFFF
    if kind == "hysteresis":
        return low, high, out_high << 8 | out_high
    return low, high, out_high << 8 | out_low


def _analog_image(model: TesModel, values: Mapping[str, Value]) -> dict[int, int]:
    image = {0x03B: _int(values, "threshold_polarity"), 0x03C: _int(values, "watchdog_100ms")}
    image[0x03D] = _int(values, "fallback.digital_command")
    image[0x046] = _int(values, "ao.fallback_enable")
    image[0x055] = _int(values, "storage_period_s")
    for k in range(8):
        low, high, outs = (0x8000, 0x7FFF, 0xFFFF)
        if k in model.analog_inputs:
            low, high, outs = _threshold_words(values, k)
        image[0x023 + k], image[0x02B + k], image[0x033 + k] = low, high, outs
        fallback = _int(values, f"ao{k}.fallback") if k in model.analog_outputs else 0
        image[0x03E + k] = _u16(fallback)
    image.update(_timing_words(values, 0x01D, 0x01F))
    return image


def _timing_words(values: Mapping[str, Value], filters: int | None, blink: int) -> dict[int, int]:
    image: dict[int, int] = {}
    if filters is not None:
        image[filters] = _int(values, "filter_0_ms") // 5  # Tb = 5 ms
        image[filters + 1] = _int(values, "filter_1_ms") // 5
    names = ("blink_a_on_ms", "blink_a_off_ms", "blink_b_on_ms", "blink_b_off_ms")
    for i, name in enumerate(names):
        image[blink + i] = _int(values, name) // 5
    return image


def _digital_image(model: TesModel, values: Mapping[str, Value]) -> dict[int, int]:
    masks = [_int(values, f"fallback.{op}_{w}") for op in ("or", "and") for w in ("blink", "state")]
    if model.family is Family.DIGITAL_OUTPUTS:
        image = _timing_words(values, None, 0x007)
        for i, mask in enumerate(masks):  # 00Eh..015h, [15..00] then [31..16]
            image[0x00E + 2 * i], image[0x00F + 2 * i] = mask & 0xFFFF, mask >> 16
    else:
        image = _timing_words(values, 0x00A, 0x00E)
        image.update({0x012 + i: mask for i, mask in enumerate(masks)})
        image[0x00D] = _int(values, "outputs.command")
    image[0x016] = _int(values, "watchdog_100ms")
    if model.safety:
        security = _int(values, "security_inputs")
        image[0x1AB], image[0x1AC] = security & 0xFFFF, security >> 16
    return image


def mp_image(model: TesModel, values: Mapping[str, Value]) -> dict[int, int]:
    """address -> word loaded into the MP registers at power-on (§1)."""
    if model.is_analog:
        return _analog_image(model, values)
    return _digital_image(model, values)
