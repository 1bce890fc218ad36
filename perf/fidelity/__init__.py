"""Fidelity: figures measured against a truth (geometry, physics, images)."""
