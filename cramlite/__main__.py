import sys

from cramlite.cli import main

sys.exit(main())
