"""The limit stage: the motion model (a path on the robot: joint motion, motor torques and their rates), the
continuous limit check with exact peaks and the report. Imports ``robots``, ``curves`` and ``model``; the
timing stage above calls it (never the other way round)."""
