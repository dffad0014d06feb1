from connenv.bench import main

main()
