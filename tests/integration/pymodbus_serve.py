"""Serves a pymodbus 3.0 context on 127.0.0.1:PORT for the peer scripts
beside it; says "serving on ..." only once the port listens.

The port is bound with SO_REUSEADDR: a restarted peer binds it again at
once while the killed one's connection lingers in TIME_WAIT. A bind that
fails ends the process with its error: pymodbus's own start-up runs the
server as a task and only logs such an error, leaving a process that is up
and never listens."""

import asyncio

from pymodbus.server import StartAsyncTcpServer


async def serve(context, port):
    server = await StartAsyncTcpServer(context, address=("127.0.0.1", port), allow_reuse_address=True,
                                       defer_start=True)
    task = asyncio.get_running_loop().create_task(server.serve_forever())
    await asyncio.wait({task, server.serving}, return_when=asyncio.FIRST_COMPLETED)
    if task.done():
        task.result()  # raises the bind's error
    print(f"serving on 127.0.0.1:{port}", flush=True)
    await task
