"""pytest-ready consistency checks (filled in by the comparison issue)."""
