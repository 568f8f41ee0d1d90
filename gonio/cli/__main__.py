"""``python -m gonio.cli``."""
from gonio.cli import main

raise SystemExit(main())
