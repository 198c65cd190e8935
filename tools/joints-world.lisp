;;;; tools/joints-world.lisp -- a world of joints for make view FILE=tools/joints-world.lisp
;;;; (physics.org, #J01NTS): a chain of twelve balls hung from a fixed point and swinging, and
;;;; beside it Newton's cradle on strings, over a floor. The last form returns the world.

(let* ((terrain (physics:make-voxel-terrain))
       (world (progn (physics:fill-terrain terrain -8 0 -8 12 12 8 nil)
                     (physics:fill-terrain terrain -8 -1 -8 12 0 8 t)
                     (physics:make-physics-world :terrain terrain :kernels :auto)))
       (chain (loop for i from 1 to 12
                    collect (physics:add-physics-body world (* 0.5 i) 8 0 :radius 0.2 :friction 0.3))))
  ;; the chain: centre to centre by stiff distance joints of 0.5 m, hung by a rope from (0 8 0)
  (physics:add-physics-joint world :distance (first chain) nil :anchor-b '(0 8 0) :rope t)
  (loop for (p q) on chain while q
        do (physics:add-physics-joint world :distance p q))
  ;; the cradle: five touching balls of restitution 1 on two strings each, the first drawn back
  (let* ((drop (sqrt 0.75)) (x0 -5.0) (z0 3.0)
         (balls (loop for i below 5
                      collect (physics:add-physics-body world (+ x0 (* i 0.5)) (- 4 drop) z0
                                                        :radius 0.25 :friction 0 :restitution 1.0))))
    (physics:set-physics-body-position world (first balls) (- x0 (* drop (sin (/ pi 6)))) (- 4 (* drop (cos (/ pi 6)))) z0)
    (loop for ball in balls for i from 0
          do (dolist (dz '(0.5 -0.5))
               (physics:add-physics-joint world :distance ball nil :anchor-b (list (+ x0 (* i 0.5)) 4 (+ z0 dz))
                                                                   :length 1.0))))
  world)
