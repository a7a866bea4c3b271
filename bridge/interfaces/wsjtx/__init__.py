"""WSJT-X's and JTDX's UDP messages, so that a rotator can follow the QSO partner: the
messages decoded (``messages``, pure, with the protocol's fact sheet) and the listener, a UDP
socket on a thread of its own handing what it hears to the rotators (``server``)."""

from bridge.interfaces.wsjtx.server import WsjtxListener

__all__ = ["WsjtxListener"]
