"""Analysis layer (rate-gyro arithmetic here; the layout moves more in)."""
