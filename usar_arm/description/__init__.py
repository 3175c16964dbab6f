"""From an arm learnt over the wire to its validated description files, and back.

* :mod:`.pipeline`: discovery record -> chain -> URDF, SRDF, joint limits, discovery.json
  (validated before anything is written);
* :mod:`.cache`: descriptions kept under a key of the CONF/GEO lines they came from, with the
  calibrated descriptions of the same arm;
* :mod:`.embedded`: the embedded simulator as a source of descriptions (the only module that
  starts it to learn an arm);
* :mod:`.accuracy`: a learnt chain against the simulator's own model.
"""
