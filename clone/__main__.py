from clone.cli.main import main

main()
