"""Command-line entry point: mantaray <command>."""
def main():
    print("ok")
