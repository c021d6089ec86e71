import sys

from pvcloth.cli import main

sys.exit(main())
