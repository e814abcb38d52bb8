"""``python -m fleetsim`` runs the command line."""

from fleetsim.cli.main import main

raise SystemExit(main())
