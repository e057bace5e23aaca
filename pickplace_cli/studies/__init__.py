"""Studies over many plans: method comparison, residual vibration, the constrained workspace and the papers'
parameter studies. Above the planner; imports it and every stage below."""
