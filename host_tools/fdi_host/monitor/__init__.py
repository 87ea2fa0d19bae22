"""Watching a diagnosis run: per-message bus statistics, silences, scoring against the ground truth and the
reports (``fdi-monitor``)."""
