"""Certificate and figures (draft Annex B)."""
