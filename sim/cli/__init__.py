"""`mantaray sim ...`: the command lines (commands.py) and one handler module per command."""
