"""Offline structural analysis of diagnosis models: model files, DM decomposition, MSO sets, isolability."""

__version__ = "0.1.0"
