"""`python -m stl_lfd.cli`: the `stlopt` program."""

from stl_lfd.cli import main

main()
