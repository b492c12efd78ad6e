-- touched
function update(dt) end
