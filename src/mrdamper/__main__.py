"""Allow ``python -m mrdamper``."""

from mrdamper.cli.launch import main

main()
