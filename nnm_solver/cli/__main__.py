"""``python -m nnm_solver.cli`` runs ``nnm-solve``."""
import sys

from .solve import main

sys.exit(main())
