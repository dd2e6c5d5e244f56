"""Post-processing of reduced states: stress recovery and location, clearance, mode classification."""
