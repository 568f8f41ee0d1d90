"""``python -m gonio.cli``."""
import sys

try:
    from gonio.cli import main
    _rc = main()
except KeyboardInterrupt:          # before main() took over (while importing)
    sys.stderr.write("gonio: interrupted\n")
    _rc = 130
raise SystemExit(_rc)
