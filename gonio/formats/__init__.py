"""File formats (rate-gyro readings here; the layout moves more in)."""
