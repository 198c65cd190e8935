;;;; tools/feature-one.lisp -- one process of make count-features (physics.org, #FBNCH9): load the
;;;; engine of the tree ROOT, build the feature scene NAME of +feature-scenes+ with every feature
;;;; (KIND general) or with the scene's own (KIND specialised), step it STEPS times, and print
;;;;   feature NAME KIND HASH
;;;; with the world's state hash.  Its start, tools/one-process.lisp, is tools/against-one.lisp's.
;;;;
;;;; Usage: sbcl --script tools/feature-one.lisp ROOT/ NAME KIND STEPS

(load (merge-pathnames "one-process.lisp" *load-truename*))

(defvar *feature-arguments* (one-process-arguments "feature-one" "ROOT/ NAME KIND STEPS" 4))

(destructuring-bind (root name kind steps) *feature-arguments*
  (declare (ignore root))
  (let* ((scene (intern (string-upcase name) :keyword))
         (entry (assoc scene (symbol-value (find-symbol "+FEATURE-SCENES+" :luv-physics))))
         (all (symbol-value (find-symbol "+PHYSICS-FEATURES+" :luv-physics)))
         (features (if (string-equal kind "specialised") (or (third entry) all) all)))
    (unless entry
      (format *error-output* "feature-one: no feature scene ~A~%" name)
      (sb-ext:exit :code 2))
    (multiple-value-bind (world before)
        (funcall (find-symbol "FEATURE-SCENE" :luv-physics) scene :features features)
      (dotimes (i (parse-integer steps))
        (when before (funcall before i))
        (funcall (find-symbol "STEP-PHYSICS-WORLD" :luv-physics) world))
      (format t "~&feature ~(~A~) ~(~A~) ~D~%" scene kind
              (funcall (find-symbol "PHYSICS-WORLD-STATE-HASH" :luv-physics) world))
      (finish-output))))
