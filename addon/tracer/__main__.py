"""`python -m addon.tracer`: the tracer's command line (see `cli`)."""

from .cli import main

raise SystemExit(main())
