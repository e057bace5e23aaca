"""pickplace: smooth, fast pick-and-place trajectory planning for high-speed robots.

Library first: ``pickplace_cli.planner.plan`` is the entry point the CLI and the tests use.
"""

__version__ = "0.1.0"
