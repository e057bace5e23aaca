"""Independent reference models the tests compare the library against (never imported by pickplace_cli)."""
