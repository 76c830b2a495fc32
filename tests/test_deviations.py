"""Every kind's Deviations rows are complete, and the generated page prints them."""

from __future__ import annotations

import re

import pytest

from devsim.cli.docgen import reference_markdown
from devsim.core.registry import device_class, kinds

SECTION = re.compile(r"§\d+(\.\d+)*")


@pytest.mark.parametrize("kind", sorted(kinds()))
def test_every_deviation_names_its_section_and_reason(kind: str) -> None:
    cls = device_class(kind)
    for row in cls.reference().deviations:
        assert SECTION.match(row.section), row
        assert row.manual.strip() and row.simulator.strip() and row.reason.strip(), row


@pytest.mark.parametrize("kind", sorted(kinds()))
def test_the_reference_page_has_a_deviations_section(kind: str) -> None:
    page = reference_markdown(device_class(kind))
    section = page.split("## Deviations", 1)[1].split("\n## ", 1)[0]
    rows = device_class(kind).reference().deviations
    assert ("None known." in section) == (not rows)
    for row in rows:
        assert row.section in section
