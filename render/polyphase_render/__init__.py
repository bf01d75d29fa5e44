"""Offline render pipeline for polyphase run folders (issue 5): Mitsuba 3 scenes built from the
labeled interface meshes, tone-mapped frames, a movie, plots of the run's statistics and `.vol`
grid export. Entry point: `python -m polyphase_render DIR` (what `polyphase render DIR` runs)."""

__version__ = "0.1.0"
