"""The foundation every layer stands on (numpy only): typed errors with their evidence and exit
codes (:mod:`.errors`), rotations and frames (:mod:`.spatial`), the data model of an arm in SI
units and REP-103 frames (:mod:`.model`), atomic file writes (:mod:`.fileio`), safe YAML
(:mod:`.yamlio`), numbers written with the precision they mean (:mod:`.precision`) and the
version (:mod:`.version`)."""
