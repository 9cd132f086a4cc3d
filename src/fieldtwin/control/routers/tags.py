"""``/tags`` and ``/trends``: the plant's tags with their values, a tagged object or
input written by its tag, and the history of a series (docs/control.md, "Tags and
trends")."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Query
from pydantic import Field

from fieldtwin.control.replies import Reply
from fieldtwin.control.resources import Conflict, Control, NotFound
from fieldtwin.control.routers.common import REPLY, Hop
from fieldtwin.control.schemas import Closed
from fieldtwin.control.trends import TooManySeries
from fieldtwin.errors import ConfigError
from fieldtwin.plant.tags import Tag, UnknownTag, raw_value, raw_word, resolve, tag_value
from fieldtwin.words import parse_word

TagNumber = bool | int | float


class TagJson(Reply):
    """A tag: its source (``{"object": "W0"}`` or ``{"device": "tes1", "input": "3"}``),
    its value now in its unit (scaled), the source's own value (``raw``) and the text."""

    name: str
    source: dict[str, str]
    source_text: str
    unit: str
    description: str
    value: TagNumber | None
    raw: TagNumber | None
    text: str
    scale: list[float] | None = None


class TrendsJson(Reply):
    """The series kept (every tag, the plant's default trends, those asked for since)
    and the default trends the dashboard opens with."""

    series: list[str]
    defaults: list[str]
    sample_s: float
    max_points: int


class TrendJson(Reply):
    """A series' points ``[t_s, value]`` after ``since`` (the last one is now), in its unit."""

    series: str
    source_text: str
    unit: str
    points: list[list[TagNumber | None]]  # [t_s, value]


class TagBody(Closed):
    """A value for a tagged object, register or input.  A number is in the tag's unit:
    a scaled tag's number is taken back to the source's raw value (a word is rounded);
    ``true``/``false`` and a text (``"on"``, ``"12mA"``) go to the source as they are."""

    value: bool | int | float | Annotated[str, Field(max_length=64)]


def _tag(c: Control, name: str) -> Tag:
    try:
        return resolve(c.plant, name)
    except UnknownTag as exc:
        raise NotFound(str(exc)) from None


def tag_json(c: Control, tag: Tag) -> dict[str, object]:
    return tag_value(c.plant, tag).json()


def raw_of(tag: Tag, value: bool | float | str) -> bool | float | str:
    """A value in the tag's unit, back to the source's (a number of a scaled tag)."""
    if tag.scale is None or isinstance(value, bool | str):
        return value
    return raw_value(tag, value)


def _word(tag: Tag, value: bool | float | str) -> int:
    if isinstance(value, str):
        return parse_word(value)
    return raw_word(tag, float(value))


def router(hop: Hop) -> APIRouter:
    c = hop.control
    api = APIRouter(tags=["tags"])

    @api.get("/tags", summary="the plant file's tags, each with its source and value now", **REPLY)
    async def tags() -> list[TagJson]:
        found = await hop.read("tags", lambda: [tag_json(c, t) for t in c.plant.tags])
        return [TagJson.model_validate(one) for one in found]

    @api.get(
        "/tags/{name}",
        summary="a tag (or a PL7 object by its name): its source and value now",
        responses={404: {"description": "no such tag (the message lists the tags)"}},
        **REPLY,
    )
    async def one_tag(name: str) -> TagJson:
        found = await hop.read(("tag", name), lambda: tag_json(c, _tag(c, name)))
        return TagJson.model_validate(found)

    @api.put(
        "/tags/{name}",
        summary="write a tagged object or register, or set a tagged input, in the tag's unit",
        responses={404: {"description": "no such tag (the message lists the tags)"}},
        **REPLY,
    )
    async def write_tag(name: str, body: TagBody) -> TagJson:
        tag = await hop.run(lambda: _tag(c, name))
        try:
            await write(tag, body.value)
        except NotFound:
            raise
        except ConfigError as exc:  # a value the tag's source does not take: 409
            raise Conflict(str(exc)) from None
        return TagJson.model_validate(await hop.run(lambda: tag_json(c, tag)))

    async def write(tag: Tag, value: bool | float | str) -> None:
        source = tag.source
        if source.kind == "output":
            raise ConfigError(
                f"tag {tag.name}: {source.text} is an output the device drives"
                " (allowed: a tag of an object, a register or an input)"
            )
        if source.kind == "input":
            assert source.device is not None
            await hop.do("set_input", source.device, source.name, raw_of(tag, value), None)
        elif source.kind == "register":
            assert source.device is not None
            await hop.do("write_object", source.device, source.name, _word(tag, value))
        else:  # a PL7 object: the console's write, a command through the door as any
            lines = await hop.sim.line(f"write {source.name} {_word(tag, value)}")
            assert isinstance(lines, list)

    @api.get("/trends", summary="the series kept and the dashboard's default trends", **REPLY)
    async def trends() -> TrendsJson:
        trends = c.trends
        return TrendsJson.model_validate(
            {
                "series": trends.names(),
                "defaults": list(c.plant.tags.trends),
                "sample_s": trends.sample_us / 1e6,
                "max_points": trends.max_points,
            }
        )

    @api.get(
        "/trends/{series}",
        summary="a series' history (a tag or an object): its points after since, then now",
        responses={404: {"description": "no such tag nor object"}},
        **REPLY,
    )
    async def trend(
        series: str,
        since: Annotated[float | None, Query(ge=0, le=1e9, description="simulated seconds")] = None,
    ) -> TrendJson:
        trends = c.trends
        tag = trends.tag(series)
        if tag is None:  # kept from now on (bounded): resolved on the simulation's thread

            def track() -> Tag:
                try:
                    return trends.track(series)
                except UnknownTag as exc:
                    raise NotFound(str(exc)) from None
                except TooManySeries as exc:
                    raise ConfigError(str(exc)) from None

            tag = await hop.run(track)
        kept = tag

        def now() -> tuple[float, TagNumber | None, str]:
            value = tag_value(c.plant, kept)
            return (c.plant.clock.now / 1e6, value.value, value.unit)

        t_s, value, unit = await hop.read(("trend-now", kept.name), now)
        points = trends.points(kept, since)
        if (not points or points[-1][0] < t_s) and (since is None or t_s > since):
            points.append((t_s, value))
        return TrendJson.model_validate(
            {"series": kept.name, "source_text": kept.source.text, "unit": unit, "points": points}
        )

    return api


__all__ = ["TagBody", "TagJson", "TrendJson", "TrendsJson", "raw_of", "router", "tag_json"]
