"""Interoperability: other tools reading or driving what marsscene makes (USD, Newton, DDS)."""
