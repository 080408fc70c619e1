"""``python3 -m rss6 ...`` runs the ``rss6`` command line (same as the console script)."""

from rss6.cli import main

raise SystemExit(main())
