"""Analysis layer: estimators that turn readings into results (no plotting)."""
