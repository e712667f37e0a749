"""`python -m roadgaze` is the same as the `roadgaze` console script."""

import sys

from roadgaze.cli import main

sys.exit(main())
