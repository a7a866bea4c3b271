"""The soak run: `python -m tests.soak --minutes 10` (not collected by pytest; see runner.py)."""
