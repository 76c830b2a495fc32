"""``python -m devsim`` – the same as the ``devsim`` command."""

from devsim.cli import main

if __name__ == "__main__":
    main(prog_name="devsim")
