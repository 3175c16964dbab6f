"""Hypothesis strategies for every USARSim message type."""

from __future__ import annotations

from hypothesis import strategies as st

from usar_arm.usarsim import messages as m

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
            "gametype", "level", "timelimit", "startposes"}
extra_keys = names.filter(lambda k: k.lower() not in RESERVED)
extras = st.lists(st.tuples(extra_keys, values), max_size=3).map(tuple)

game_info = st.builds(m.GameInfo, names, names, st.none() | floats, extras)
start_poses = st.builds(m.StartPoses, st.lists(st.builds(m.StartPose, names, vectors, vectors),
                                               max_size=4).map(tuple))
inits = st.builds(m.Init, names, st.none() | names, st.none() | names, st.none() | vectors,
                  st.none() | vectors, extras)
get_confs = st.builds(m.GetConf, names, st.none() | names)
get_geos = st.builds(m.GetGeo, names, st.none() | names)
acts = st.builds(m.Act, names, st.lists(st.tuples(ints, floats), max_size=8).map(tuple),
                 st.none() | ints, st.none() | ints, extras)
sets = st.builds(m.Set, names, names, names, st.none() | values)
drives = st.builds(m.Drive, st.none() | floats, st.none() | floats, st.none() | st.booleans(),
                   st.none() | st.booleans(), extras)
link_confs = st.builds(m.LinkConf, ints, names, st.none() | floats, st.none() | floats,
                       st.none() | floats, st.none() | floats, extras)
conf_items = st.builds(m.ConfItem, names, extras, st.lists(link_confs, max_size=4).map(tuple))
confs = st.builds(m.Conf, names.filter(lambda t: t.lower() != "name"),
                  st.lists(conf_items, min_size=1, max_size=3).map(tuple))
platform_confs = st.builds(m.PlatformConf, names, names, extras)
link_geos = st.builds(m.LinkGeo, ints, ints, vectors, vectors, extras)
geo_items = st.builds(m.GeoItem, names, st.none() | vectors, st.none() | vectors,
                      st.none() | names, st.none() | ints,
                      st.lists(link_geos, max_size=4).map(tuple), st.none() | vectors, extras)
geos = st.builds(m.Geo, names, st.lists(geo_items, min_size=1, max_size=3).map(tuple))
astas = st.builds(m.Asta, floats, names, st.lists(st.tuples(ints, floats), max_size=8).map(tuple),
                  extras)
stas = st.builds(m.Sta, floats, st.none() | ints, st.none() | names, extras)
sens = st.builds(m.Sen, names, names, st.none() | floats, st.none() | vectors,
                 st.none() | vectors, extras)
effs = st.builds(m.Eff, names, names, st.none() | floats, extras)
HEADS = {"NFO", "GETSTARTPOSES", "INIT", "GETCONF", "GETGEO", "ACT", "SET", "DRIVE", "CONF",
         "GEO", "ASTA", "STA", "SEN", "EFF"}
unknowns = st.builds(m.Unknown, names.filter(lambda h: h.upper() not in HEADS),
                     st.lists(st.tuples(names, values), max_size=4).map(tuple))

ALL = {
    "GameInfo": game_info, "StartPoses": start_poses, "GetStartPoses": st.just(m.GetStartPoses()),
    "Init": inits, "GetConf": get_confs, "GetGeo": get_geos, "Act": acts, "Set": sets,
    "Drive": drives, "Conf": confs, "PlatformConf": platform_confs, "Geo": geos, "Asta": astas,
    "Sta": stas, "Sen": sens, "Eff": effs, "Unknown": unknowns,
}
messages = st.one_of(*ALL.values())
