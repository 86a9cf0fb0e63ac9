"""`python -m hertz_chain ...`: the `hertz-chain` command line (`hertz_chain.cli.main`), for a working copy
or an environment without the console script."""

from .cli import main

if __name__ == "__main__":
    main()
