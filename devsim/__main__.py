"""``python -m devsim`` – the same as the ``devsim`` command."""

from devsim.cli import cli

if __name__ == "__main__":
    cli.main(prog_name="devsim")
