"""Review 70 (37397651): datagrams.py rule 8 passes over "a UTF-8 byte-order mark and one XML
declaration" in front of ``<PST>``/``<N1MMRotor>``, "as an XML parser would", and nothing else.
But ``_PROLOG`` takes ``<?xml`` and any 200 bytes up to ``?>`` for a declaration: one with no
version, plain junk, or bytes that are not ASCII (rule 1 judges what follows the prolog only),
none of which an XML parser reads (expat: "XML declaration not well-formed", "invalid token").
Each such datagram, Malformed before the change and for any XML reader, now turns the rotor.
"""

from __future__ import annotations

import xml.parsers.expat

import pytest

from bridge.interfaces.loggers.datagrams import Malformed, parse_n1mm, parse_pst

_TURN_PST = b"<PST><AZIMUTH>85</AZIMUTH></PST>"
_TURN_N1MM = b"<N1MMRotor><rotor>Tower</rotor><goazi>85</goazi></N1MMRotor>"

_NO_DECLARATIONS = [
    b"<?xml?>",  # no version: a declaration must have one
    b"<?xml rm -rf / ?>",  # junk
    b'<?xml version="1.0" \xff\xfe\xfd?>',  # bytes that are not ASCII (rule 1)
]


def _xml_reads(datagram: bytes) -> bool:
    parser = xml.parsers.expat.ParserCreate()
    try:
        parser.Parse(datagram, True)
    except xml.parsers.expat.ExpatError:
        return False
    return True


@pytest.mark.parametrize("head", _NO_DECLARATIONS)
def test_no_xml_reader_takes_these_heads(head: bytes) -> None:
    """The test's premise: none of them is an XML declaration."""
    assert not _xml_reads(head + _TURN_PST)
    assert not _xml_reads(head + _TURN_N1MM)


@pytest.mark.parametrize("head", _NO_DECLARATIONS)
def test_what_is_no_xml_declaration_in_front_moves_nothing(head: bytes) -> None:
    with pytest.raises(Malformed):  # observed: PstRequest(azimuth=85.0)
        parse_pst(head + _TURN_PST)
    with pytest.raises(Malformed):  # observed: N1mmRequest('Tower', azimuth=85.0)
        parse_n1mm(head + _TURN_N1MM)
