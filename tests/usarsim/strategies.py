"""Hypothesis strategies for every USARSim message type.

:func:`build` makes one strategy per message type from strategies for its parts, so the same
message shapes can be drawn over different domains:

* ``ALL`` (and ``messages``): the everyday domain (ASCII names, numbers within +-1e6).
* ``WIDE``: everything the grammar can carry: every finite float64 (subnormals, -0.0, +-1.8e308),
  integers up to +-2**128, Unicode text in values and names.
* ``UDK_EXACT``: numbers UDK's formats print exactly (see :func:`build`'s arguments).
"""

from __future__ import annotations

from dataclasses import dataclass

from hypothesis import strategies as st

from usar_arm.usarsim import messages as m
from usar_arm.usarsim.codec import SEN_TYPES

# Names: what USARSim component and robot names look like (no spaces, braces or commas).
names = st.text(alphabet=st.characters(whitelist_categories=("Lu", "Ll", "Nd"),
                                       whitelist_characters="_.-", max_codepoint=127),
                min_size=1, max_size=12)
# Free-form values: may contain spaces and commas, never braces; trimmed as UDK trims them.
_BAD = "{}\r\n\t\x0b\x0c\x1c\x1d\x1e\x1f\x85\xa0"
values = st.text(alphabet=st.characters(blacklist_characters=_BAD,
                                        blacklist_categories=("Cs", "Zl", "Zp", "Cc")),
                 min_size=1, max_size=20).map(str.strip).filter(bool)
floats = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False, allow_infinity=False)
vectors = st.tuples(floats, floats, floats)
ints = st.integers(min_value=-1000, max_value=1000)
RESERVED = {"name", "type", "link", "value", "time", "location", "orientation", "mount",
            "mountlink", "tip", "parent", "parentlink", "jointtype", "maxtorque", "minvalue",
            "maxvalue", "maxspeed", "gripper", "sequence", "seq", "battery", "classname",
            "start", "rotation", "opcode", "params", "left", "right", "normalized", "light",
            "speed", "frontsteer", "rearsteer",
            "gametype", "level", "timelimit", "startposes", "resolution", "fov", "range",
            "pose", "holding", "object", "count", "pair", "first", "last", "depth", "steps",
            "size", "memory", "scale", "physics", "permanent", "material", "minpos", "maxpos"}
HEADS = {"NFO", "GETSTARTPOSES", "INIT", "GETCONF", "GETGEO", "ACT", "SET", "DRIVE", "CONF",
         "GEO", "ASTA", "STA", "SEN", "EFF", "CONTROL"}

# ------------------------------------------------------------------------ the wide domain
# Any character a decoded line can hold except the two the grammar reserves ('{', '}'), the line
# terminators, and surrogates (no UTF-8 decoder produces them).
_wide_char = st.characters(blacklist_categories=("Cs",), blacklist_characters="{}\r\n")
wide_tokens = st.text(alphabet=_wide_char.filter(lambda c: not c.isspace()), min_size=1,
                      max_size=12)
"""Text without whitespace: keys, command words, start-pose names (they are split at spaces)."""
wide_values = st.text(alphabet=_wide_char, max_size=20).map(str.strip)
"""Any value text, possibly empty (``{On}``); UDK trims values, so these come trimmed."""
finite = st.floats(allow_nan=False, allow_infinity=False)
wide_ints = st.integers(min_value=-(2**128), max_value=2**128)

# --------------------------------------------------------------------- the UDK-exact domain
udk_scalars = st.integers(-(10**11), 10**11).map(lambda k: k / 10**4)
"""4-decimal numbers (Time, ASTA/ACT Value, CONF limits): UDK prints them with %.4f."""
udk_raw = st.integers(-(10**13), 10**13).map(lambda k: k / 100)
"""2-decimal numbers (start poses, INIT vectors, GEO link orientations, Tip): printed %.2f."""
udk_fixed = st.integers(-(2**23), 2**23).map(lambda k: k / 8)
"""Multiples of 1/8 m within +-2**20 (FloatString fields: GEO locations, GroundTruth poses):
exact in float32 and in 3 decimals, so the float32 truncation UDK applies loses nothing."""
udk_float32_range = st.floats(min_value=-1e38, max_value=1e38, allow_nan=False)
"""Any float that FloatString's float32 arithmetic can hold (+-3.4e38)."""


@dataclass(frozen=True)
class Domain:
    """The parts messages are built from.

    Attributes:
        scalar: raw engine floats (Time, Value, CONF limits, TimeLimit, DRIVE speeds).
        raw: components of raw vectors (start poses, INIT Location/Rotation, GEO link
            Orientation, Tip).
        fixed: components of FloatString vectors (GEO item and link Location, item Orientation,
            SEN Location/Orientation).
        ints: link numbers, parents, Gripper, Sequence, MountLink, Battery.
        names: single-word text (start-pose names, extra keys, command words of unknown lines).
        values: text in a value position (names of components, types, opcodes...).
    """

    scalar: st.SearchStrategy[float]
    raw: st.SearchStrategy[float]
    fixed: st.SearchStrategy[float]
    ints: st.SearchStrategy[int]
    names: st.SearchStrategy[str]
    values: st.SearchStrategy[str]
    ranges: st.SearchStrategy[float] | None = None
    """Scanner ranges (FloatString(r, 2)); None: the ``fixed`` numbers."""


def build(d: Domain) -> dict[str, st.SearchStrategy[m.Message]]:
    """One strategy per message type (keyed by class name) over the domain ``d``."""
    raw_v = st.tuples(d.raw, d.raw, d.raw)
    fixed_v = st.tuples(d.fixed, d.fixed, d.fixed)
    extra_keys = d.names.filter(lambda k: k.lower() not in RESERVED)
    extras = st.lists(st.tuples(extra_keys, d.values), max_size=3).map(tuple)
    opt = st.none

    link_confs = st.builds(m.LinkConf, d.ints, d.values, opt() | d.scalar, opt() | d.scalar,
                           opt() | d.scalar, opt() | d.scalar, extras)
    conf_items = st.builds(m.ConfItem, d.values, extras,
                           st.lists(link_confs, max_size=4).map(tuple))
    link_geos = st.builds(m.LinkGeo, d.ints, d.ints, fixed_v, raw_v, extras)
    geo_items = st.builds(m.GeoItem, d.values, opt() | fixed_v, opt() | fixed_v,
                          opt() | d.values, opt() | d.ints,
                          st.lists(link_geos, max_size=4).map(tuple), opt() | raw_v, extras)
    pairs = st.lists(st.tuples(d.ints, d.scalar), max_size=8).map(tuple)
    ranges = st.lists(d.ranges if d.ranges is not None else d.fixed, max_size=12).map(tuple)

    def spelled(word: str) -> st.SearchStrategy[str]:
        return st.sampled_from([word, word.lower(), word.upper()])
    return {
        "GameInfo": st.builds(m.GameInfo, d.values, d.values, opt() | d.scalar, extras),
        "StartPoses": st.builds(m.StartPoses, st.lists(
            st.builds(m.StartPose, d.names, raw_v, raw_v), max_size=4).map(tuple)),
        "GetStartPoses": st.just(m.GetStartPoses()),
        "Init": st.builds(m.Init, d.values, opt() | d.values, opt() | d.values, opt() | raw_v,
                          opt() | raw_v, extras),
        "GetConf": st.builds(m.GetConf, d.values, opt() | d.values),
        "GetGeo": st.builds(m.GetGeo, d.values, opt() | d.values),
        "Act": st.builds(m.Act, d.values, pairs, opt() | d.ints, opt() | d.ints, extras),
        "Set": st.builds(m.Set, d.values, d.values, d.values, opt() | d.values),
        "Drive": st.builds(m.Drive, opt() | d.scalar, opt() | d.scalar, opt() | st.booleans(),
                           opt() | st.booleans(), extras, opt() | d.scalar, opt() | d.scalar,
                           opt() | d.scalar),
        "Conf": st.builds(m.Conf, d.values, st.lists(conf_items, min_size=1, max_size=3)
                          .map(tuple)),
        "PlatformConf": st.builds(m.PlatformConf, d.values, d.values, extras),
        "Geo": st.builds(m.Geo, d.values, st.lists(geo_items, min_size=1, max_size=3).map(tuple)),
        "Asta": st.builds(m.Asta, d.scalar, d.values, pairs, extras),
        "Sta": st.builds(m.Sta, d.scalar, opt() | d.ints, opt() | d.values, extras),
        "Sen": st.builds(m.Sen, d.values.filter(lambda t: t.lower() not in SEN_TYPES),
                         d.values, opt() | d.scalar, opt() | fixed_v, opt() | fixed_v, extras),
        "RangeScan": st.builds(m.RangeScan, d.values, d.fixed, d.fixed, ranges, opt() | d.scalar,
                               spelled("RangeScanner"), extras),
        "Ins": st.builds(m.Ins, d.values, raw_v, raw_v, opt() | d.scalar, spelled("INS"), extras),
        "Odometry": st.builds(m.Odometry, d.values, st.tuples(d.scalar, d.scalar, d.scalar),
                              opt() | d.scalar, spelled("Odometry"), extras),
        "Eff": st.builds(m.Eff, d.values, d.values, opt() | d.scalar, extras),
        "Control": st.builds(m.Control, d.values, *([opt() | d.values] * 12), extras),
        "WcStatus": st.builds(m.WcStatus, st.lists(st.builds(
            m.WcObjectStatus, d.values, fixed_v, fixed_v, st.just("") | d.values, fixed_v),
            max_size=3).map(tuple)),
        "ContactReport": st.builds(m.ContactReport, d.values, st.lists(st.builds(
            m.ContactPair, d.names, d.names, d.scalar, d.scalar, d.scalar, d.ints),
            max_size=3).map(tuple), opt() | d.scalar, spelled("Contact")),
        "GripTruth": st.builds(m.GripTruth, d.values, st.booleans(), opt() | d.values,
                               opt() | d.scalar, spelled("GripTruth"), extras),
        "Unknown": st.builds(m.Unknown, d.names.filter(lambda h: h.upper() not in HEADS),
                             st.lists(st.tuples(d.names, d.values), max_size=4).map(tuple)),
    }


EVERYDAY = Domain(floats, floats, floats, ints, names, values)
WIDE_DOMAIN = Domain(finite, finite, finite, wide_ints, wide_tokens, wide_values)
udk_quarters = st.integers(-(2**20), 2**20).map(lambda k: k / 4)
"""Multiples of 1/4 m (scanner ranges): exact in float32 and in FloatString(r, 2)."""
UDK_EXACT_DOMAIN = Domain(udk_scalars, udk_raw, udk_fixed, wide_ints, wide_tokens, wide_values,
                          udk_quarters)
UDK_ANY_DOMAIN = Domain(udk_float32_range, udk_float32_range, udk_float32_range, wide_ints,
                        wide_tokens, wide_values)

ALL = build(EVERYDAY)
WIDE = build(WIDE_DOMAIN)
UDK_EXACT = build(UDK_EXACT_DOMAIN)
UDK_ANY = build(UDK_ANY_DOMAIN)
messages = st.one_of(*ALL.values())
