"""Values every layer shares (the command union, states, error kinds, bearings on the
globe, the bands) and small helpers (rate limits, an on-demand thread): the standard
library only, nothing of the bridge (docs/architecture.md, Layout)."""
