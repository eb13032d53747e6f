"""Everything that is not drawing: no textual import anywhere below here."""
