;;;; tools/example-world.lisp -- a world of one's own for the viewer: make view FILE=tools/example-world.lisp
;;;; Read in the package luv-physics-user (CL and LUV-PHYSICS); the last form's value is the world.
;;;; A floor 40 m long, a wall at its far end, and a row of balls rolling towards it.

(let ((terrain (make-voxel-terrain)))
  (fill-terrain terrain 0 0 0 40 6 8 nil)     ; air, resident, where the balls roll
  (fill-terrain terrain 0 -1 0 40 0 8 t)      ; the floor, its top at y = 0
  (fill-terrain terrain 36 0 0 37 3 8 t)      ; a wall 3 m high at x = 36
  (let ((world (make-physics-world :terrain terrain :sleep t)))
    (dotimes (i 6)
      (let ((h (add-physics-body world (+ 2.0 (* 0.6 i)) 0.3 (+ 1.5 i) :radius 0.25 :friction 0.6)))
        (set-physics-body-velocity world h 6.0 0.0 0.0)))
    world))
