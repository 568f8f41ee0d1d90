"""``python -m gonio``."""
from gonio.cli import main

raise SystemExit(main())
