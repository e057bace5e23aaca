"""The value objects every stage shares: errors (exit codes), the task, the Cartesian path and trajectory, the
profile (pydantic) and where the shipped data lives. Imports nothing else of the package."""
