"""The threads, ports and files around the sessions: the serial-lines thread,
the workers, the judge front ends call, the state file (docs/architecture.md, Layout)."""
