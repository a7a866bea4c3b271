"""DX cluster spots: the line and cty parsers (sans-IO), the spots kept, the telnet client."""

from bridge.interfaces.dxcluster.book import Book
from bridge.interfaces.dxcluster.client import DxCluster
from bridge.interfaces.dxcluster.cty import Cty, CtyError, load

__all__ = ["Book", "Cty", "CtyError", "DxCluster", "load"]
