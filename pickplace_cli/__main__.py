from pickplace_cli.cli import main

main()
