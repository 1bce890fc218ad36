"""The rover and its sensor suite as data: run configuration (:mod:`.config`), geometry and
wheel kinematics (:mod:`.geometry`). Pure numpy; no MuJoCo, no files."""
