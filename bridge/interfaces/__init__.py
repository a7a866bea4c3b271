"""Every way into and out of the bridge, one package each, and the line
servers two of them share (docs/architecture.md, Layout)."""
