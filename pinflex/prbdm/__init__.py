"""Pseudo-rigid-body dynamic models (PRBDM) of compliant beams (paper 001)."""
