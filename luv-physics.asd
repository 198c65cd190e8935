;;;; luv-physics.asd -- the systems tangled from physics.org.  Edit physics.org, not the tangled files.

(defsystem "luv-physics"
  :description "Rigid spheres in a voxel world, written as the literate page physics.org."
  :depends-on ((:require "sb-simd") (:require "sb-introspect"))
  ;; one line per file compiled: the compiler's notes are for the page's authors
  ;; each file is compiled after a full collection, so the second file's compilation does not
  ;; run in a heap still holding the garbage of the first
  :around-compile (lambda (compile)
                    (sb-ext:gc :full t)
                    (let* ((log (make-string-output-stream))
                           (started (get-internal-real-time))
                           (result (multiple-value-list
                                    (let ((*standard-output* log) (*compile-verbose* t) (*compile-print* nil))
                                      (handler-bind ((sb-ext:compiler-note #'muffle-warning))
                                        (funcall compile)))))
                           (text (get-output-stream-string log))
                           (at (search "; compiling file \"" text))
                           (file (if at
                                     (subseq text (+ at 18) (position #\" text :start (+ at 18)))
                                     "a file")))
                      (format *error-output* "~&; luv-physics: compiled ~A in ~,1F s~%"
                              (enough-namestring file (asdf:system-source-directory "luv-physics"))
                              (/ (- (get-internal-real-time) started) internal-time-units-per-second))
                      (values-list result)))
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
