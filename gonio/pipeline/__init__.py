"""Pipelines (rate-gyro pipelines here; the layout moves calibrate, validate, demo in)."""
