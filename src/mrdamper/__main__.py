"""Allow ``python -m mrdamper``."""

from mrdamper.cli.main import main

main()
