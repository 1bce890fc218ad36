"""``python -m marsscene`` runs the command line."""

from marsscene.cli import main

main()
