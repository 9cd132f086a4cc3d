import sys

from fieldtwin.cli import main

sys.exit(main())
