"""A line of robots on one belt (stage 9, above ``pipelines``): the line file, the parts, the engine that shares
the parts out and plans every pick, the results, sweeps."""
