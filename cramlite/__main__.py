from cramlite.cli import console

console()
