"""Measured performance of rotor-bridge, side by side with the line rate and Hamlib's rotctld.

`python -m benchmarks` runs everything (see __main__.py); not part of the test run. Modules:
one per item (latency, freshness, line_use, footprint, burst, startup, console), the plumbing
they share (harness: processes, broker, bridge service, MQTT recorder; line: a serial line paced
at its real rate; rig: a measured set-up; emuhost: a process hosting many emulated controllers;
hamlib: rotctld; procfs: CPU and memory of another process; report: statistics and tables),
satel_redirect, a stand-alone scenario, and floor (with floor_engine): exchange_cpu's scenario
run by a minimal engine written for the measurement, beside the bridge.
"""
