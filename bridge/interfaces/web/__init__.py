"""The operator console's pure groundwork: the station's map projection (``projection``) and
the coastlines it draws (``land-110m.json``, written by scripts/make-land-map from Natural Earth
1:110m land; read from the package, never fetched at run time)."""
