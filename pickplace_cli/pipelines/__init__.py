"""Many moves: batch files and streams, the batched verdict engine, timelines of round trips, the conveyor
rendezvous and ``check`` of a trajectory file. Above the planner; imports it and every stage below."""
