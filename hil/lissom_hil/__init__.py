"""Lissom host-side Python: plotting, benchmarks and the CAN HIL rig."""
