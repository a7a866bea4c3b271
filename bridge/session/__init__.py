"""Every decision about one rotator, sans-IO: the session, the parts its step
calls, the controller as seen through its line (docs/architecture.md, Layout)."""
