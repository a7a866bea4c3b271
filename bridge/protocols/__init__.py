"""Controller families. REGISTRY maps the configuration's ``model`` name to its ModelSpec."""

from bridge.protocols.base import ModelSpec
from bridge.protocols.easycomm import MODELS as _EASYCOMM
from bridge.protocols.gs232 import MODELS as _GS232
from bridge.protocols.prosistel import MODELS as _PROSISTEL
from bridge.protocols.rc2800 import MODELS as _RC2800
from bridge.protocols.rotorez import MODELS as _ROTOREZ
from bridge.protocols.rt21 import MODELS as _RT21
from bridge.protocols.satel import MODELS as _SATEL
from bridge.protocols.spid import MODELS as _SPID

REGISTRY: dict[str, ModelSpec] = {
    **_ROTOREZ,
    **_SPID,
    **_SATEL,
    **_GS232,
    **_EASYCOMM,
    **_RT21,
    **_PROSISTEL,
    **_RC2800,
}
