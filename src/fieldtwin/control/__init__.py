"""The control API of a running plant: REST/JSON resources, the event stream, the client.

The web server (FastAPI on Starlette, served by uvicorn) runs in its own thread;
every command is handed to the runner through an inbox and executed on the
simulation's thread between two instants (docs/control.md).
"""
