;;;; luv-physics.asd -- the systems tangled from physics.org.  Edit physics.org, not the tangled files.

(defsystem "luv-physics"
  :description "Rigid spheres in a voxel world, written as the literate page physics.org."
  :depends-on ((:require "sb-simd") (:require "sb-introspect"))
  :serial t
  :components ((:file "tangled/physics")
               (:file "tangled/physics-simd"))
  :in-order-to ((test-op (test-op "luv-physics/tests"))))

(defsystem "luv-physics/tests"
  :description "The claims of physics.org, as FiveAM tests."
  :depends-on ("luv-physics" "fiveam")
  :components ((:file "tests/physics-tests"))
  :perform (test-op (o c)
             (uiop:symbol-call '#:fiveam '#:run!
                               (uiop:find-symbol* '#:claims '#:luv-physics-tests))))
