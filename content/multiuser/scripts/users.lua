-- Who is here: the server tells scripts when a node's user joins and leaves.
present = {}
joins = 0

on("userJoined", function(user)
  present[user] = true
  joins = joins + 1
  log(user .. " joined")
end)

on("userLeft", function(user)
  present[user] = nil
  log(user .. " left")
end)
