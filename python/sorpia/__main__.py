"""``python -m sorpia``: the same program as the ``sorpia`` script."""

from .cli import main

raise SystemExit(main())
