"""Fixtures of the live tests: ``dds_xml``, a Cyclone DDS configuration that keeps a test's
DDS traffic on 127.0.0.1 (multicast off; :data:`fretc.live.dds.idl_types.LOOPBACK_XML`)."""

import pytest


@pytest.fixture()
def dds_xml(tmp_path) -> str:
    """The path of the loopback configuration, written into the test's own folder."""
    from fretc.live.dds.idl_types import LOOPBACK_XML

    path = tmp_path / "loopback.xml"
    path.write_text(LOOPBACK_XML, encoding="utf-8")
    return str(path)
