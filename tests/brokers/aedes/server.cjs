// aedes, as Node-RED's node-red-contrib-aedes embeds it, on 127.0.0.1:<port> for the broker
// matrix (tests/support/brokers.py starts it; scripts/bootstrap installs aedes here: npm ci).
const aedes = require('aedes')()
const server = require('node:net').createServer(aedes.handle)
const port = Number(process.argv[2])
server.listen(port, '127.0.0.1', () => console.log(`aedes listening on ${port}`))
process.on('SIGTERM', () => {
  server.close()
  aedes.close(() => process.exit(0))
})
