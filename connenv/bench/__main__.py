from connenv import cli
from connenv.bench import PROG, main

cli.run(main, PROG)
