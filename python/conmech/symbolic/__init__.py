"""conmech.symbolic (in progress)."""
