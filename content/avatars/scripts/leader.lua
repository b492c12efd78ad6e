-- The leader: R runs (a 0.5 s crossfade), W walks again, SPACE waves and then walks on
-- (a queue: the wave ends, onAnimationEnd tells us, the walk fades back in).

function onKey(key, pressed)
  if not pressed then return end
  if key == "r" then
    self:blend({Walk = 0, Run = 1}, {fade = 0.5})
  elseif key == "w" then
    self:blend({Walk = 1, Run = 0}, {fade = 0.5})
  elseif key == "space" then
    self:play("Wave", {fade = 0.2})
    self:queue({Walk = 1, Run = 0}, {fade = 0.3})
  end
end

function onAnimationEnd(clip)
  log("leader finished " .. clip)
end
