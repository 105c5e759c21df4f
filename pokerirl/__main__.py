from pokerirl.cli import app

app(prog_name="pokerirl")
