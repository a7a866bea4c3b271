"""DX cluster spots: the line and cty parsers (sans-IO), the spots kept, the telnet client."""

from bridge.dxcluster.book import Book
from bridge.dxcluster.client import DxCluster
from bridge.dxcluster.cty import Cty, CtyError, load

__all__ = ["Book", "Cty", "CtyError", "DxCluster", "load"]
